#include "core/declared_units.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "core/metadata.hpp"

namespace canalsim {
namespace {

bool is_level(const std::string& name) {
  return name == columns::upstream_level || name == columns::level_below_gate ||
         name == columns::level_downstream_end || name.rfind("y_check", 0) == 0;
}

}  // namespace

DeclaredUnit declared_unit(const Recording& rec, const std::string& which) {
  const std::string source = rec.source.empty() ? "recording" : rec.source;
  const std::string unit_key = which + "_unit", scale_key = which + "_scale_mm_per_unit";
  const std::string unit = rec.meta(unit_key);
  const std::optional<double> scale = metadata_number(rec, scale_key);
  if (!scale) {
    // Length units every logger may name without a scale.
    if (unit == "m") return {unit, 1000.0};
    if (unit == "cm") return {unit, 10.0};
    if (!unit.empty() && unit != "mm") {
      throw InputError(source + ": metadata " + unit_key + ": " + unit + " needs " + scale_key + " (how many mm one " +
                       unit + " is, e.g. # " + scale_key + ": 0.13)");
    }
    return {};
  }
  return {unit.empty() ? "unit" : unit, *scale};
}

Recording in_millimetres(Recording rec) {
  const std::string source = rec.source.empty() ? "recording" : rec.source;
  const DeclaredUnit u = declared_unit(rec, "u"), y = declared_unit(rec, "y");
  for (std::size_t c = 0; c < rec.names.size(); ++c) {
    const std::string& name = rec.names[c];
    const bool command = name == columns::gate_command || name == columns::gate_position;
    const double scale = command ? u.mm_per_unit : is_level(name) ? y.mm_per_unit : 1.0;
    if (scale == 1.0) continue;
    for (std::size_t row = 0; row < rec.columns[c].size(); ++row) {
      double& v = rec.columns[c][row];
      v *= scale;
      if (std::abs(v) > kMaxRecordedMagnitude) {
        throw InputError(rec.where(row) + ": column " + name + ": " + format_g(v / scale) + " " +
                         (command ? u.name : y.name) + " is " + format_g(v) + " mm: expected a magnitude of at most " +
                         format_g(kMaxRecordedMagnitude) + " mm (check " + (command ? "u" : "y") +
                         "_scale_mm_per_unit)");
      }
    }
  }
  for (const char* which : {"u", "y"}) {
    if (rec.meta(std::string(which) + "_unit").empty() && rec.meta(std::string(which) + "_scale_mm_per_unit").empty()) {
      continue;
    }
    rec.set_meta(std::string(which) + "_unit", "mm");
    rec.set_meta(std::string(which) + "_scale_mm_per_unit", "1");
  }
  return rec;
}

}  // namespace canalsim
