#include "plot/ticks.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"

namespace canalsim::plot {
namespace {

// m × 10^e written so that a negative exponent divides: 3 × 10⁻¹ is 3 / 10 = 0.3 exactly as
// printed, where 3 × 0.1 would be 0.30000000000000004.
double scaled(double m, int e) { return e >= 0 ? m * std::pow(10.0, e) : m / std::pow(10.0, -e); }

int decimal_exponent(double v) { return static_cast<int>(std::floor(std::log10(v) + 1e-9)); }

bool is_negative_zero_text(const std::string& s) {
  if (s.empty() || s[0] != '-') return false;
  return s.find_first_not_of("-0.") == std::string::npos;
}

}  // namespace

double nice_step(double raw) {
  if (!(raw > 0.0) || !std::isfinite(raw)) return 1.0;
  const int e = decimal_exponent(raw);
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    const double step = scaled(m, e);
    if (step >= raw * (1.0 - 1e-9)) return step;
  }
  return scaled(10.0, e);
}

double tick_step(double low, double high, int target) {
  const double span = high - low;
  if (!(span > 0.0)) {
    const double magnitude = std::max(std::abs(low), std::abs(high));
    return magnitude > 0.0 ? nice_step(magnitude / 10.0) : 1.0;
  }
  return nice_step(span / std::max(target, 1));
}

std::vector<double> ticks_at(double low, double high, double step) {
  std::vector<double> out;
  if (!(step > 0.0) || !std::isfinite(low) || !std::isfinite(high) || high < low) return out;
  const double tolerance = 1e-9 * std::max(high - low, step);
  const double first = std::ceil((low - tolerance) / step), last = std::floor((high + tolerance) / step);
  if (last - first > 1000.0) return out;  // a step far too small for the range: no axis reads that
  const int e = decimal_exponent(step);
  const double mantissa = std::round(step / scaled(1.0, e) * 1e6) / 1e6;  // 1, 2 or 5 (or any step's leading part)
  for (double k = first; k <= last; k += 1.0) out.push_back(k == 0.0 ? 0.0 : scaled(k * mantissa, e));
  return out;
}

std::vector<double> nice_ticks(double low, double high, int target) {
  return ticks_at(low, high, tick_step(low, high, target));
}

std::string tick_label(double value, double step) {
  if (value == 0.0 || !std::isfinite(value)) return "0";
  std::string text;
  if (step >= 1e-4 && step < 1e6 && std::abs(value) < 1e9) {
    const int decimals = std::max(0, -decimal_exponent(step));
    text = format_fixed(value, decimals);
  } else {
    const int digits = std::clamp(decimal_exponent(std::abs(value)) - decimal_exponent(step) + 1, 1, 15);
    text = format_g(value, digits);
  }
  return is_negative_zero_text(text) ? "0" : text;
}

std::vector<double> log_decades(double low, double high) {
  std::vector<double> out;
  if (!(low > 0.0) || !(high >= low)) return out;
  for (int e = static_cast<int>(std::ceil(std::log10(low) - 1e-9)); e <= static_cast<int>(std::floor(std::log10(high) + 1e-9)); ++e) {
    out.push_back(scaled(1.0, e));
  }
  return out;
}

std::vector<double> log_minor_ticks(double low, double high) {
  std::vector<double> out;
  if (!(low > 0.0) || !(high >= low)) return out;
  for (int e = static_cast<int>(std::floor(std::log10(low))); e <= static_cast<int>(std::floor(std::log10(high))); ++e) {
    for (int m = 2; m <= 9; ++m) {
      const double v = scaled(m, e);
      if (v >= low * (1.0 - 1e-9) && v <= high * (1.0 + 1e-9)) out.push_back(v);
    }
  }
  return out;
}

std::string log_tick_label(double value) {
  if (value >= 1e-3 && value <= 1e4) return format_g(value, 6);
  return format_g(value, 1);
}

}  // namespace canalsim::plot
