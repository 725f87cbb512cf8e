// docs/scenarios.md and the scenario validator agree key by key: every numeric range in the
// documentation's tables is loaded at its bounds (accepted) and just outside them (refused with
// an error naming the key). A key whose documented range changes without the validator (or the
// other way round) fails here.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "scenarios/scenario_toml.hpp"

namespace {

using canalsim::InputError;

struct DocumentedKey {
  std::string section;  // TOML table: "", "upstream", "pools.offtakes", ...
  std::string key;
  std::string range;    // the table's range cell
};

// The section a table belongs to: the first `[name]` or `[[name]]` of the heading or paragraph
// that introduces it ("## Top level" is the root).
std::optional<std::string> section_of(const std::string& line) {
  if (line.rfind("## Top level", 0) == 0) return std::string();
  if (line.rfind("## ", 0) != 0 && line.rfind("`[", 0) != 0) return std::nullopt;
  static const std::regex table(R"(`\[\[?([a-z_.]+)\]\]?`)");
  std::smatch m;
  if (!std::regex_search(line, m, table)) return std::nullopt;
  return m[1].str();
}

std::vector<DocumentedKey> documented_keys() {
  std::ifstream in(std::string(CANALSIM_SOURCE_DIR) + "/docs/scenarios.md");
  std::vector<DocumentedKey> keys;
  std::string line, section;
  static const std::regex row(R"(^\| `([a-z_0-9]+)` \|[^|]*\| ([^|]*) \|)");
  while (std::getline(in, line)) {
    if (const auto s = section_of(line)) section = *s;
    std::smatch m;
    if (std::regex_search(line, m, row)) keys.push_back({section, m[1].str(), m[2].str()});
  }
  return keys;
}

// The scenario every case starts from: one of each table, loading cleanly. Walls are 100 m high
// so that no "at most the wall height" constraint narrows a documented range below its bound.
using Table = std::map<std::string, std::string>;
struct Base {
  std::vector<std::pair<std::string, Table>> tables = {
      {"", {{"name", "\"docs\""}}},
      {"upstream", {{"kind", "\"discharge\""}, {"discharge_m3s", "0.001"}}},
      {"head_gate", {{"width_m", "0.08"}, {"max_opening_m", "0.05"}, {"opening_m", "0.02"}, {"controlled", "true"}}},
      {"[pools]", {{"length_m", "5"}, {"bottom_width_m", "0.08"}, {"wall_height_m", "100"}}},
      {"[pools.offtakes]", {{"x_m", "1"}, {"discharge_m3s", "0.0001"}}},
      {"downstream", {{"kind", "\"gate\""}}},
      {"downstream.gate", {{"width_m", "0.08"}, {"max_opening_m", "0.05"}, {"opening_m", "0.03"}}},
      {"sensors", {}},
      {"numerics", {}},
      {"[experiments]", {{"name", "\"e1\""}, {"operating_opening_mm", "20"}}},
      {"experiments.input", {{"kind", "\"prbs\""}}},
      {"experiments.sensors", {}},
      {"[experiments.events]", {{"t_s", "1"}, {"pool", "1"}, {"offtake_m3s", "0.0002"}}},
      {"calibration", {}},
      {"calibration.std", {}},
  };
  // Documented bounds that name another key, as the base scenario sets them.
  std::map<std::string, double> symbols = {
      {"`max_opening_m`", 0.05}, {"`wall_height_m`", 100.0}, {"last pool length", 5.0}, {"`length_m`", 5.0},
      {"previous event's `t_s`", 0.0}, {"number of pools", 1.0}, {"offtakes in the pool", 1.0}, {"gate max", 50.0}};

  std::string toml(const std::string& section, const std::string& key, const std::string& value) const {
    std::string text;
    for (const auto& [header, entries] : tables) {
      const bool array = !header.empty() && header.front() == '[';
      const std::string name = array ? header.substr(1, header.size() - 2) : header;
      if (!header.empty()) text += (array ? "[[" + name + "]]" : "[" + name + "]") + "\n";
      Table t = entries;
      if (name == section) t[key] = value;
      for (const auto& [k, v] : t) text += k + " = " + v + "\n";
    }
    return text;
  }
};

std::string dotted(const DocumentedKey& k) {
  // Arrays of tables are reported with their index: pools[0].cells, experiments[0].events[0].t_s.
  std::string path = k.section;
  for (const char* array : {"experiments.events", "pools.offtakes"}) {
    if (path == array) path = std::string(array).replace(std::string(array).find('.'), 1, "[0].") + "[0]";
  }
  if (path == "pools" || path == "experiments") path += "[0]";
  if (path == "experiments.input" || path == "experiments.sensors") path.replace(11, 1, "[0].");
  return path.empty() ? k.key : path + "." + k.key;
}

struct Interval {
  double low, high;
  bool low_open, high_open;
};

std::optional<double> bound(const std::string& text, const Base& base) {
  if (text == "∞") return INFINITY;
  if (const auto it = base.symbols.find(text); it != base.symbols.end()) return it->second;
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::optional<Interval> interval(const std::string& range, const Base& base) {
  static const std::regex pattern(R"(^([\[(])([^,]+), ([^\])]+)([\])]))");
  std::smatch m;
  if (!std::regex_search(range, m, pattern)) return std::nullopt;
  const auto low = bound(m[2].str(), base), high = bound(m[3].str(), base);
  if (!low || !high) return std::nullopt;
  return Interval{*low, *high, m[1].str() == "(", m[4].str() == ")"};
}

bool is_integer_key(const std::string& key) {
  return key == "cells" || key == "stages" || key == "pool" || key == "offtake" || key == "order";
}

std::string text_of(double v, bool integer) {
  if (integer) return std::to_string(static_cast<long long>(v));
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  std::string s = buffer;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

// (value, accepted) pairs: each finite bound, and a value just past it.
std::vector<std::pair<double, bool>> probes(const Interval& r, bool integer) {
  std::vector<std::pair<double, bool>> out;
  auto step = [integer](double b) { return integer ? 1.0 : std::max(std::abs(b) * 1e-6, 1e-9); };
  if (std::isfinite(r.low)) {
    out.emplace_back(r.low_open ? r.low + step(r.low) : r.low, true);
    out.emplace_back(r.low_open ? r.low : r.low - step(r.low), false);
  }
  if (std::isfinite(r.high)) {
    out.emplace_back(r.high_open ? r.high - step(r.high) : r.high, true);
    out.emplace_back(r.high_open ? r.high : r.high + step(r.high), false);
  }
  return out;
}

TEST(DocsRanges, TheBaseScenarioLoads) {
  const Base base;
  EXPECT_NO_THROW(canalsim::scenarios::parse_scenario(base.toml("", "description", "\"base\""), "docs.toml"));
}

TEST(DocsRanges, EveryDocumentedNumericRangeIsTheValidatorsRange) {
  const Base base;
  const auto keys = documented_keys();
  ASSERT_GT(keys.size(), 60u) << "docs/scenarios.md tables not found";
  std::size_t checked = 0;
  for (DocumentedKey k : keys) {
    if (k.section == "head_gate" && k.key == "controlled") continue;
    const auto range = interval(k.range, base);
    if (!range) continue;  // strings, choices, booleans, seeds
    const bool integer = is_integer_key(k.key);
    // [experiments.sensors] takes the same keys as [sensors] ("same keys"): check both.
    std::vector<std::string> sections = {k.section};
    if (k.section == "sensors") sections.push_back("experiments.sensors");
    for (const auto& section : sections) {
      k.section = section;
      for (const auto& [value, accepted] : probes(*range, integer)) {
        const std::string text = text_of(value, integer);
        const std::string toml = base.toml(section, k.key, text);
        const std::string what = dotted(k) + " = " + text + " (documented " + k.range + ")";
        try {
          canalsim::scenarios::parse_scenario(toml, "docs.toml");
          EXPECT_TRUE(accepted) << what << ": accepted, but the docs exclude it";
        } catch (const InputError& e) {
          const std::string message = e.what();
          // Inside its range a key may still be refused for another key's sake (a wall lower than
          // the gate's max_opening_m); never with its own name.
          if (accepted) {
            EXPECT_EQ(message.find(dotted(k) + " ="), std::string::npos) << what << ": refused: " << message;
          }
          if (!accepted) {
            EXPECT_NE(message.find(dotted(k)), std::string::npos) << what << ": " << message;
          }
        }
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 150u);
}

// The message shows a refused value as given, not rounded onto the bound it exceeds.
TEST(DocsRanges, AValueJustPastABoundIsPrintedDistinctly) {
  const Base base;
  try {
    canalsim::scenarios::parse_scenario(base.toml("numerics", "cfl", "1.0000001"), "docs.toml");
    FAIL() << "cfl = 1.0000001 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("numerics.cfl = 1.0000001: expected a number in (0, 1]"), std::string::npos)
        << e.what();
  }
}

TEST(DocsRanges, AHugeFieldIsNotEchoedWhole) {
  const Base base;
  const std::string huge(1 << 20, 'x');
  try {
    canalsim::scenarios::parse_scenario(base.toml("upstream", "kind", "\"" + huge + "\""), "docs.toml");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_LT(message.size(), 400u);
    EXPECT_NE(message.find("(1048576 characters)"), std::string::npos) << message.substr(0, 400);
  }
}

TEST(DocsRanges, TheDownstreamGateCanBeTheControlledOne) {
  Base base;
  base.tables[2].second["controlled"] = "false";
  base.tables[6].second["controlled"] = "true";
  EXPECT_NO_THROW(canalsim::scenarios::parse_scenario(base.toml("", "description", "\"d\""), "docs.toml"));
}

}  // namespace
