// Text pieces shared by the study's claims and renderers (internal to study/).
#pragma once

#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/format.hpp"
#include "reduced_models/identification.hpp"
#include "reduced_models/models.hpp"

namespace canalsim::study {

using reduced::ModelKind;

// A fitted parameter: fixed decimals, except a small non-zero value (the nonlinear models' scale
// K / H^γ at a large γ, ~1e-10) keeps three significant digits instead of printing as 0.0000.
inline std::string parameter_fmt(double v, int digits) {
  if (std::isfinite(v) && v != 0.0 && std::abs(v) < 0.01) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.3g", v);
    return buffer;
  }
  return format_fixed(v, digits);
}

// Δp of eq. (22) divides by the nominal parameter: a nominal γ of 0 (the linear form) makes it
// undefined, which the table says instead of printing a bare infinity.
inline std::string uncertainty_cell(double index) {
  return std::isfinite(index) ? format_fixed(100.0 * index, 2) : "∞ (nominal 0)";
}

inline std::string signed_fmt(double v, int digits) {
  if (!std::isfinite(v)) return format_fixed(v, digits);
  std::string out = v >= 0 ? "+" : "";
  out += format_fixed(v, digits);
  return out;
}

// "a", "a and b", "a, b and c".
inline std::string join_and(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += (i + 1 == items.size()) ? " and " : ", ";
    out += items[i];
  }
  return out;
}

inline std::string join_comma(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + items[i];
  return out;
}

inline std::string upper_name(ModelKind kind) {
  std::string n = model_name(kind);
  for (auto& c : n) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return n;
}


// The paper's scale of a parameter: K of nonlinear models is K / H^γ (levels in mm).
inline double here_parameter(const reduced::Model& m, const std::string& name) {
  if (name == "K" && reduced::uses_upstream_level(m.kind)) return reduced::paper_gain(m);
  return reduced::get_parameter(m.p, name);
}

}  // namespace canalsim::study
