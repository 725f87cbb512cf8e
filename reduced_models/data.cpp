#include "reduced_models/data.hpp"

#include "core/declared_units.hpp"
#include "core/format.hpp"
#include "core/metadata.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace canalsim::reduced {
namespace {

constexpr double kMinResponseMm = 1.0e-6;

// The recording's operating_opening_mm metadata (checked by the reader, core/metadata.hpp).
std::optional<double> operating_point_mm(const Recording& recording) {
  return metadata_number(recording, "operating_opening_mm");
}

}  // namespace

double declared_gain_factor(const ExperimentData& data) {
  return data.u_scale_mm_per_unit / data.y_scale_mm_per_unit;
}

std::string declared_gain_unit(const ExperimentData& data) { return data.y_unit + "/" + data.u_unit; }

Status DataOptions::validate() const {
  return Validator()
      .require(!upstream_level_mm || (std::isfinite(*upstream_level_mm) && *upstream_level_mm > 0.0),
               "upstream_level_mm", upstream_level_mm.value_or(0.0), "a positive level in mm")
      .require(!u0_mm || std::isfinite(*u0_mm), "u0_mm", u0_mm.value_or(0.0), "a finite value")
      .require(!y0_mm || std::isfinite(*y0_mm), "y0_mm", y0_mm.value_or(0.0), "a finite value")
      .require(rest_samples_max >= 1, "rest_samples_max", static_cast<double>(rest_samples_max), "at least 1")
      .require(min_excitation_mm >= 0.0, "min_excitation_mm", min_excitation_mm, ">= 0")
      .status();
}

ExperimentData prepare_data(const Recording& recording, const DataOptions& options) {
  const std::string source = recording.source.empty() ? "recording" : recording.source;
  if (const Status status = options.validate(); !status) throw InputError(source + ": data options: " + status.message());
  ExperimentData d;
  d.source = source;
  // The columns in mm, each checked against kMaxRecordedMagnitude after its declared unit applies.
  const Recording in_mm = in_millimetres(recording);
  d.t_s = in_mm.column(columns::time);
  d.u_mm = in_mm.column(columns::gate_command);
  d.y_dwe_mm = in_mm.column(columns::level_downstream_end);
  if (d.t_s.size() < 2) {
    throw InputError(source + ": expected at least two samples, found " +
                     std::to_string(d.t_s.size()));
  }
  d.h = recording.sample_period();
  if (in_mm.has(columns::upstream_level)) {
    d.y_up_mm = in_mm.column(columns::upstream_level);
  } else if (options.upstream_level_mm) {
    d.y_up_mm.assign(d.size(), *options.upstream_level_mm);
    d.y_up_is_constant_option = true;
  }
  if (in_mm.has(columns::gate_position)) d.x_up_mm = in_mm.column(columns::gate_position);
  const DeclaredUnit u_unit = declared_unit(recording, "u"), y_unit = declared_unit(recording, "y");
  d.u_unit = u_unit.name;
  d.u_scale_mm_per_unit = u_unit.mm_per_unit;
  d.y_unit = y_unit.name;
  d.y_scale_mm_per_unit = y_unit.mm_per_unit;

  const auto [umin, umax] = std::minmax_element(d.u_mm.begin(), d.u_mm.end());
  if (*umax - *umin <= options.min_excitation_mm) {
    throw InputError(source + ": u_mm is constant (" + format_g(*umin) +
                     " mm): the input has no excitation, so no model can be identified "
                     "(expected e.g. a PRBS around the operating point)");
  }
  const auto [ymin, ymax] = std::minmax_element(d.y_dwe_mm.begin(), d.y_dwe_mm.end());
  if (*ymax == *ymin) {
    throw InputError(source + ": y_dwe_mm is constant (" + format_g(*ymin) +
                     " mm in every row): the level never responds to the input, so no model can be "
                     "identified and the Nrmse (eq. 19) is undefined (expected the recorded downstream level)");
  }
  // A response no level sensor resolves (a nanometre) is rounding noise or a unit mistake, and its
  // squares underflow in the fits' costs.
  if (*ymax - *ymin < kMinResponseMm) {
    throw InputError(source + ": y_dwe_mm varies by only " + format_g(*ymax - *ymin) + " mm: expected a response of at least " +
                     format_g(kMinResponseMm) + " mm (check the unit, or y_scale_mm_per_unit)");
  }
  // The operating point the input moves about: the recording's `operating_opening_mm` metadata
  // when it has one (the canal settled there before the PRBS started, which may begin on +5 mm),
  // else the first command.
  d.u0_mm = options.u0_mm.value_or(operating_point_mm(recording).value_or(d.u_mm.front()));
  if (options.y0_mm) {
    d.y0_mm = *options.y0_mm;
  } else {
    std::size_t rest = 1;
    while (rest < d.size() && rest < options.rest_samples_max && d.u_mm[rest] == d.u_mm[0]) ++rest;
    d.y0_mm = std::accumulate(d.y_dwe_mm.begin(), d.y_dwe_mm.begin() + static_cast<long>(rest), 0.0) /
              static_cast<double>(rest);
  }
  return d;
}

ExperimentData load_experiment(const std::string& file, const DataOptions& options) {
  return prepare_data(read_recording(file), options);
}

void require_upstream_level(const ExperimentData& data, const std::string& model_name) {
  if (!data.has_upstream_level()) {
    throw InputError(data.source + ": model " + model_name +
                     " needs the upstream level: the recording has no y_up_mm column (add it, "
                     "or give a constant upstream level, e.g. --upstream-level 60)");
  }
}

ExperimentData leading_samples(const ExperimentData& data, std::size_t n) {
  ExperimentData out = data;
  for (auto* v : {&out.t_s, &out.u_mm, &out.y_dwe_mm, &out.y_up_mm, &out.x_up_mm}) {
    if (v->size() > n) v->resize(n);
  }
  return out;
}

ExperimentData block_average(const ExperimentData& data, std::size_t factor) {
  if (factor <= 1) return data;
  ExperimentData out = data;
  const std::size_t blocks = std::max<std::size_t>(1, data.size() / factor);
  const auto average = [&](const std::vector<double>& v) {
    if (v.empty()) return v;
    std::vector<double> a(blocks, 0.0);
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t begin = b * factor, end = std::min(v.size(), begin + factor);
      a[b] = std::accumulate(v.begin() + static_cast<long>(begin), v.begin() + static_cast<long>(end), 0.0) /
             static_cast<double>(end - begin);
    }
    return a;
  };
  out.t_s = average(data.t_s);
  out.u_mm = average(data.u_mm);
  out.y_dwe_mm = average(data.y_dwe_mm);
  out.y_up_mm = average(data.y_up_mm);
  out.x_up_mm = average(data.x_up_mm);
  out.h = data.h * static_cast<double>(factor);
  return out;
}

}  // namespace canalsim::reduced
