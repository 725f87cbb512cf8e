// The last check before a result is printed: every figure of a fit or a diagnosis is a finite
// number. A NaN or infinity that slipped through (an overflow inside an optimiser, a 0/0 of a
// degenerate recording) becomes one error line naming the stage and the figure, never "-nan%"
// in a table with exit status 0.
#pragma once

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "core/errors.hpp"

namespace canalsim::cli {

// Throws InputError "STAGE: FIGURE is not finite (nan)" for the first non-finite number in `j`,
// FIGURE being its JSON path (fits[0].nrmse[0]).
inline void require_finite_figures(const nlohmann::json& j, const std::string& stage, const std::string& path = "") {
  if (j.is_number_float()) {
    const double v = j.get<double>();
    if (!std::isfinite(v)) {
      throw InputError(stage + ": " + (path.empty() ? std::string("a figure") : path) + " is not finite (" +
                       (std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf")) +
                       "): the recordings are degenerate or out of range for this model");
    }
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      require_finite_figures(it.value(), stage, path.empty() ? it.key() : path + "." + it.key());
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      // A finite number needs no path: a series of 10⁵ samples is checked without building one.
      if (j[i].is_number() && (!j[i].is_number_float() || std::isfinite(j[i].get<double>()))) continue;
      require_finite_figures(j[i], stage, path + "[" + std::to_string(i) + "]");
    }
  }
}

}  // namespace canalsim::cli
