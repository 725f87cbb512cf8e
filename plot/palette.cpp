#include "plot/palette.hpp"

#include <array>
#include <cctype>
#include <string>
#include <utility>

namespace canalsim::plot {
namespace {

// Colour-blind-safe hues (Tableau 10 and Okabe–Ito), none used twice.
constexpr std::array<std::pair<std::string_view, std::string_view>, 17> kNamed{{
    {"recorded", "#222222"},  {"measured", "#222222"}, {"nominal", "#1f77b4"},  {"calibrated", "#2ca02c"},
    {"corrected", "#e6550d"}, {"pde", "#7f7f7f"},      {"liom", "#9467bd"},     {"lfom", "#d62728"},
    {"nliom-s", "#17becf"},   {"nliom-f", "#8c564b"},  {"nlfom-s", "#e377c2"},  {"nlfom-f", "#bcbd22"},
    {"id", "#393b79"},        {"idz", "#637939"},      {"command", "#6b6b6b"},  {"u", "#6b6b6b"},
    {"y_up", "#e69f00"},
}};

constexpr std::array<std::string_view, 6> kOthers{"#009e73", "#cc79a7", "#56b4e9", "#d55e00", "#6a3d9a", "#f0a30a"};

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

std::string named_colour(std::string_view name) {
  const std::string key = lower(name);
  for (const auto& [n, colour] : kNamed) {
    if (key == n) return std::string(colour);
  }
  return "";
}

std::string series_colour(std::string_view name, std::size_t index) {
  std::string colour = named_colour(name);
  return colour.empty() ? std::string(kOthers[index % kOthers.size()]) : colour;
}

}  // namespace canalsim::plot
