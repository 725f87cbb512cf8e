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

}  // namespace

double calibration_uncertainty(Effect effect, const scenarios::Scenario& s, const std::map<std::string, double>& stds,
                               double operating_opening_mm) {
  if (stds.empty()) return 0.0;
  switch (effect) {
    case Effect::discharge_coefficient:
    case Effect::lateral_outflow: return discharge_relative_std(s, stds);
    case Effect::gate_leakage: return discharge_relative_std(s, stds) * std::max(operating_opening_mm, 0.0);
    case Effect::friction: return manning_relative_std(s, stds);
    case Effect::downstream_gate: return std_of(stds, "downstream_opening_mm");
    case Effect::sensor_offset: return std::hypot(std_of(stds, "offset_mm"), std_of(stds, "offset_y_dwe_mm"));
    case Effect::sensor_delay: return std_of(stds, "sensor_delay_s");
    case Effect::gate_rate_limit:
    case Effect::sensor_quantization: return 0.0;
  }
  return 0.0;
}

bool calibration_spanned_by(Effect added, Effect refitted) {
  return refitted == Effect::discharge_coefficient && added == Effect::gate_leakage;
}

double departure(Effect effect, double parameter) {
  if (effect == Effect::friction) return std::abs(std::log(parameter));
  if (effect == Effect::gate_rate_limit) return 0.0;
  return std::abs(parameter - no_effect_parameter(effect));
}

}  // namespace canalsim::diagnosis
