#include "sweep/cases.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include "calibration/scenario_file.hpp"
#include "core/format.hpp"
#include "scenarios/scenario_toml.hpp"

namespace canalsim::sweep {
namespace {

// Two uniform numbers in (0, 1] for key `key` at `point`: the Mersenne Twister and seed_seq are
// specified bit for bit by the standard (the library's distributions are not), and the 53 high
// bits of a draw make a double exactly.
std::pair<double, double> uniform_pair(std::uint64_t seed, std::size_t point, std::size_t key) {
  const auto low = [](std::uint64_t v) { return static_cast<std::uint32_t>(v & 0xffffffffu); };
  const auto high = [](std::uint64_t v) { return static_cast<std::uint32_t>(v >> 32); };
  const auto p = static_cast<std::uint64_t>(point);
  std::seed_seq sequence{low(seed), high(seed), low(p), high(p), static_cast<std::uint32_t>(key)};
  std::mt19937_64 rng(sequence);
  const auto unit = [&rng] { return (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53; };
  const double first = unit();
  return {first, unit()};
}

// A standard normal number by Box and Muller (1958) from two uniform ones.
double standard_normal(const std::pair<double, double>& u) {
  return std::sqrt(-2.0 * std::log(u.first)) * std::cos(2.0 * std::numbers::pi * u.second);
}

double draw(const Distribution& d, const std::pair<double, double>& u) {
  switch (d.kind) {
    case DistributionKind::uniform: return d.first + (d.second - d.first) * (1.0 - u.first);  // in [low, high)
    case DistributionKind::normal: return d.first + d.second * standard_normal(u);
    case DistributionKind::lognormal: return d.first * std::exp(d.second * standard_normal(u));
  }
  return d.first;
}

// The scenario key a variation edits for an experiment: "experiment.KEY" is KEY of the
// experiment's [[experiments]] entry.
std::string scenario_key(const std::string& key, int experiment_entry) {
  const std::string prefix = "experiment.";
  if (key.rfind(prefix, 0) != 0) return key;
  return "experiments[" + std::to_string(experiment_entry) + "]." + key.substr(prefix.size());
}

}  // namespace

std::size_t grid_point_count(const SweepFile& sweep) {
  std::size_t points = 1;
  for (const auto& v : sweep.vary) points *= v.is_grid() ? v.grid.size() : 1;
  return points;
}

std::size_t case_count(const SweepFile& sweep) {
  return grid_point_count(sweep) * static_cast<std::size_t>(sweep.draws) * sweep.experiments.size();
}

Case case_at(const SweepFile& sweep, std::size_t index) {
  Case c;
  c.index = index;
  c.experiment = index % sweep.experiments.size();
  c.point = index / sweep.experiments.size();
  std::size_t grid_point = c.point / static_cast<std::size_t>(sweep.draws);
  c.values.resize(sweep.vary.size());
  // Mixed radix, the last grid key fastest.
  for (std::size_t k = sweep.vary.size(); k-- > 0;) {
    const Variation& v = sweep.vary[k];
    if (!v.is_grid()) continue;
    c.values[k] = v.grid[grid_point % v.grid.size()];
    grid_point /= v.grid.size();
  }
  for (std::size_t k = 0; k < sweep.vary.size(); ++k) {
    if (const auto& d = sweep.vary[k].distribution) c.values[k] = draw(*d, uniform_pair(*sweep.seed, c.point, k));
  }
  return c;
}

std::string exact_number(double value) {
  // "%.17g" writes an integer below 10^15 without an exponent or a point: a TOML integer, which
  // keys such as cells require. Any other value gets the shortest text that reads back as it.
  if (value == std::trunc(value) && std::abs(value) < 1e15) return format_g(value, 17);
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value).ptr);
}

std::string case_scenario_text(const SweepFile& sweep, const Case& c) {
  const int entry = sweep.experiment_entries[c.experiment];
  std::vector<calibration::KeyEdit> edits;
  if (sweep.duration_s) {
    edits.push_back({"experiments[" + std::to_string(entry) + "].duration_s", 0.0, "", exact_number(*sweep.duration_s)});
  }
  for (std::size_t k = 0; k < c.values.size(); ++k) {
    edits.push_back({scenario_key(sweep.vary[k].key, entry), 0.0, "", exact_number(c.values[k])});
  }
  return calibration::edit_scenario_toml(sweep.scenario_text, edits);
}

scenarios::Scenario case_scenario(const SweepFile& sweep, const Case& c) {
  return scenarios::parse_scenario(case_scenario_text(sweep, c), sweep.scenario_source);
}

}  // namespace canalsim::sweep
