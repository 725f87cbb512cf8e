#include "core/format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace canalsim {

std::string format_g(double value, int significant) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant, value);
  return buffer;
}

std::string format_fixed(double value, int decimals) {
  if (!std::isfinite(value)) return value > 0 ? "∞" : (value < 0 ? "-∞" : "n/a");
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

std::string format_figure(double value, int decimals, const std::string& unit) {
  return std::isfinite(value) ? format_fixed(value, decimals) + unit : "-";
}

std::string format_estimate(double value, double std) {
  if (!std::isfinite(value)) return format_fixed(value, 0) + " (± n/a)";  // an unlimited gate speed: ∞
  if (!(std > 0.0) || !std::isfinite(std)) return format_g(value, 4) + " (± n/a)";
  const int decimals = std::clamp(1 - static_cast<int>(std::floor(std::log10(std))), 0, 12);
  return format_fixed(value, decimals) + " ± " + format_fixed(std, decimals);
}

std::string format_excerpt(const std::string& text) {
  constexpr std::size_t kShown = 60;
  if (text.size() <= kShown) return text;
  std::size_t cut = kShown;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;  // not inside a character
  return text.substr(0, cut) + "... (" + std::to_string(text.size()) + " characters)";
}

}  // namespace canalsim
