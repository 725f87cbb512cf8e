#include "core/declared_units.hpp"

#include <cmath>
#include <cstdlib>
#include <string>

#include "core/errors.hpp"

namespace canalsim {
namespace {

// Millimetres per declared unit of "u" (the command) or "y" (the levels); 1 without a declaration.
double declared_scale(const Recording& rec, const std::string& which) {
  const std::string source = rec.source.empty() ? "recording" : rec.source;
  const std::string unit_key = which + "_unit", scale_key = which + "_scale_mm_per_unit";
  const std::string unit = rec.meta(unit_key), text = rec.meta(scale_key);
  if (text.empty()) {
    if (!unit.empty() && unit != "mm") {
      throw InputError(source + ": metadata " + unit_key + ": " + unit + " needs " + scale_key + " (how many mm one " +
                       unit + " is, e.g. # " + scale_key + ": 0.13)");
    }
    return 1.0;
  }
  char* end = nullptr;
  const double scale = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(scale) || !(scale > 0.0)) {
    throw InputError(source + ": metadata " + scale_key + ": '" + text + "', expected a positive number of mm per unit");
  }
  return scale;
}

bool is_level(const std::string& name) {
  return name == columns::upstream_level || name == columns::level_below_gate ||
         name == columns::level_downstream_end || name.rfind("y_check", 0) == 0;
}

}  // namespace

Recording in_millimetres(Recording rec) {
  const double u_scale = declared_scale(rec, "u"), y_scale = declared_scale(rec, "y");
  for (std::size_t c = 0; c < rec.names.size(); ++c) {
    const std::string& name = rec.names[c];
    const double scale = name == columns::gate_command || name == columns::gate_position ? u_scale
                         : is_level(name)                                                ? y_scale
                                                                                         : 1.0;
    if (scale == 1.0) continue;
    for (double& v : rec.columns[c]) v *= scale;
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
