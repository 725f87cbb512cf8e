#include "diagnosis/calibrated.hpp"

#include <algorithm>
#include <cmath>

namespace canalsim::diagnosis {
namespace {

double std_of(const std::map<std::string, double>& stds, const std::string& name) {
  const auto it = stds.find(name);
  return it == stds.end() || !std::isfinite(it->second) ? 0.0 : it->second;
}

// Relative std of the head gate's discharge coefficients.
double discharge_relative_std(const scenarios::Scenario& s, const std::map<std::string, double>& stds) {
  if (!s.head_gate) return 0.0;
  const double free = s.head_gate->discharge_coefficient, submerged = s.head_gate->submerged_coefficient();
  return std::max(free > 0.0 ? std_of(stds, "cd_free") / free : 0.0,
                  submerged > 0.0 ? std_of(stds, "cd_submerged") / submerged : 0.0);
}

double manning_relative_std(const scenarios::Scenario& s, const std::map<std::string, double>& stds) {
  double out = 0.0;
  for (std::size_t i = 0; i < s.pools.size(); ++i) {
    const double n = s.pools[i].manning_n;
    const double sd = std::max(std_of(stds, "manning_n"), std_of(stds, "manning_n." + std::to_string(i + 1)));
    if (n > 0.0) out = std::max(out, sd / n);
  }
  return out;
}

// The offsets a calibration fits: offset_mm (every level sensor) and offset_<channel> (one);
// a row on every channel overlaps the shared one only.
double level_offset_std(const Effect& effect, const std::map<std::string, double>& stds) {
  const double shared = std_of(stds, "offset_mm");
  if (effect.channel.empty()) return shared;
  return std::hypot(shared, std_of(stds, "offset_" + effect.channel));
}

}  // namespace

double calibration_uncertainty(const Effect& effect, const scenarios::Scenario& s,
                               const std::map<std::string, double>& stds, double operating_opening_mm) {
  if (stds.empty()) return 0.0;
  switch (effect.kind->overlap) {
    case Overlap::discharge: return discharge_relative_std(s, stds);
    case Overlap::discharge_times_opening: return discharge_relative_std(s, stds) * std::max(operating_opening_mm, 0.0);
    case Overlap::manning: return manning_relative_std(s, stds);
    case Overlap::downstream_opening: return std_of(stds, "downstream_opening_mm");
    case Overlap::level_offset: return level_offset_std(effect, stds);
    case Overlap::clock: return std_of(stds, "sensor_delay_s");
    case Overlap::none: return 0.0;
  }
  return 0.0;
}

bool calibration_spanned_by(const Effect& added, const Effect& refitted) {
  return added.kind->spanned_by && refitted.kind->name == std::string(added.kind->spanned_by);
}

double departure(const Effect& effect, double parameter) {
  if (effect.kind->coordinate == Coordinate::inverse) return 0.0;
  return std::abs(to_theta(effect, parameter) - effect.kind->theta_none);
}

}  // namespace canalsim::diagnosis
