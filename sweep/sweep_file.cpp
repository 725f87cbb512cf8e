#include "sweep/sweep_file.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string_view>

#include <toml++/toml.h>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/format.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/toml_table.hpp"
#include "sweep/cases.hpp"

namespace canalsim::sweep {
namespace {

using scenarios::Range;
using scenarios::TomlTable;

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr int kMaxGridCount = 100000;
constexpr int kMaxDraws = 100000;
// More cases than this is a mistyped count, not a sweep: a million cases of the lab canal take
// weeks on one machine.
constexpr double kMaxCases = 1.0e6;

std::string where(const std::string& source, const toml::node& node) {
  return source + ":" + std::to_string(node.source().begin.line);
}

std::string dotted(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

// Every key of `table` must be one of `known`: a misspelt key would otherwise be ignored and the
// sweep run without it.
void reject_unknown_keys(const toml::table& table, const std::string& source, const std::string& path,
                         std::initializer_list<std::string_view> known) {
  for (const auto& [key, node] : table) {
    if (std::find(known.begin(), known.end(), key.str()) != known.end()) continue;
    std::string list;
    for (const auto name : known) {
      if (!list.empty()) list += ", ";
      list += name;
    }
    throw InputError(where(source, node) + ": unknown key " + format_excerpt(dotted(path, std::string(key.str()))) +
                     ": expected one of " + list + " (docs/sweep.md)");
  }
}

// The strings of an array key, each checked by `check` (which throws naming the element's line).
template <class Check>
std::vector<std::string> read_strings(const toml::table& table, const std::string& source, const std::string& path,
                                      const std::string& key, const std::string& expected, Check check) {
  const toml::node* node = table.get(key);
  const toml::array* array = node ? node->as_array() : nullptr;
  if (node && !array) throw InputError(where(source, *node) + ": " + dotted(path, key) + ": expected an array of " + expected);
  std::vector<std::string> out;
  if (!array) return out;
  for (const auto& element : *array) {
    const auto text = element.value<std::string>();
    if (!element.is_string()) throw InputError(where(source, element) + ": " + dotted(path, key) + ": expected " + expected);
    check(*text, where(source, element));
    if (std::find(out.begin(), out.end(), *text) != out.end()) {
      throw InputError(where(source, element) + ": " + dotted(path, key) + ": \"" + format_excerpt(*text) +
                       "\" is listed twice: expected each once");
    }
    out.push_back(*text);
  }
  return out;
}

// ---- the base scenario and its experiments ----------------------------------------------------

// A built-in name, else a path relative to the sweep file's folder (as scenario_toml_text takes
// built-in names first).
void read_base_scenario(TomlTable& top, const std::filesystem::path& folder, SweepFile& f) {
  if (!top.has("scenario")) top.fail("scenario", "missing: expected a built-in scenario name or a path to a scenario file");
  f.scenario = top.string("scenario", "");
  for (const auto& b : scenarios::builtin_scenarios()) {
    if (b.name == f.scenario) {
      f.scenario_source = "builtin:" + b.name;
      f.scenario_text = b.toml;
      return;
    }
  }
  const std::filesystem::path path = folder / f.scenario;  // an absolute path stays as it is
  std::error_code ec;
  if (f.scenario.empty() || !std::filesystem::is_regular_file(path, ec)) {
    std::string names;
    for (const auto& b : scenarios::builtin_scenarios()) names += (names.empty() ? "" : ", ") + b.name;
    top.fail_value("scenario", f.scenario,
                   "expected a built-in scenario (" + names + ") or a scenario file relative to the sweep file (" +
                       path.string() + " is not a file)");
  }
  f.scenario_source = path.string();
  f.scenario_text = read_text_file(path, "scenario file");
}

void read_experiments(const toml::table& root, const std::string& source, const scenarios::Scenario& base,
                      SweepFile& f) {
  std::string names;
  for (const auto& e : base.experiments) names += (names.empty() ? "" : ", ") + e.name;
  f.experiments = read_strings(root, source, "", "experiments", "experiment names", [&](const std::string& name, const std::string& line) {
    if (!base.find_experiment(name)) {
      throw InputError(line + ": experiments: \"" + format_excerpt(name) + "\" is not an experiment of " + f.scenario_source +
                       ": expected one of " + names);
    }
  });
  if (f.experiments.empty()) {
    const toml::node* node = root.get("experiments");
    throw InputError((node ? where(source, *node) : source + ":1") + ": experiments: missing or empty: expected the experiments to run at every point, e.g. "
                     "experiments = [\"op1\"] (" + f.scenario_source + " has " + names + ")");
  }
  for (const auto& name : f.experiments) {
    const auto* e = base.find_experiment(name);
    f.experiment_entries.push_back(static_cast<int>(e - base.experiments.data()) + 1);
  }
}

// ---- [[vary]] ---------------------------------------------------------------------------------

int line_of(const toml::table& table, const char* key) { return static_cast<int>(table.get(key)->source().begin.line); }

std::vector<double> grid_from_list(const toml::table& entry, const std::string& source, const std::string& path,
                                   std::vector<int>& lines) {
  const toml::node* node = entry.get("values");
  const toml::array* array = node->as_array();
  if (!array) throw InputError(where(source, *node) + ": " + path + ".values: expected an array of numbers");
  if (array->empty()) throw InputError(where(source, *node) + ": " + path + ".values: empty: expected at least one number");
  std::vector<double> values;
  for (const auto& element : *array) {
    const auto v = element.value<double>();
    if (!(element.is_integer() || element.is_floating_point()) || !v || !std::isfinite(*v)) {
      throw InputError(where(source, element) + ": " + path + ".values: expected finite numbers");
    }
    values.push_back(*v);
    lines.push_back(static_cast<int>(element.source().begin.line));
  }
  return values;
}

// from/to/count: `count` values from `from` to `to` (both included), evenly spaced or, with
// spacing = "log", evenly in the logarithm. The ends are exactly the numbers written.
std::vector<double> grid_from_range(TomlTable& entry) {
  for (const char* key : {"from", "to", "count"}) {
    if (!entry.has(key)) entry.fail(key, "missing: a range needs from, to and count");
  }
  const Range any{-kInfinity, kInfinity, true, true};
  const double from = entry.number("from", 0.0, any, "");
  const double to = entry.number("to", 0.0, any, "");
  const int count = entry.integer("count", 1, 1, kMaxGridCount);
  const bool log = entry.choice("spacing", "linear", {"linear", "log"}) == "log";
  if (count == 1 && from != to) entry.fail("count", "1 with from != to: expected count >= 2, or from = to for one value");
  if (count > 1 && from == to) entry.fail("to", "equal to from: expected a range of distinct ends (or values = [x])");
  if (log && !(from > 0.0 && to > 0.0)) entry.fail("spacing", "\"log\" needs from > 0 and to > 0");
  std::vector<double> values(static_cast<std::size_t>(count), from);
  for (int k = 1; k < count; ++k) {
    const double share = static_cast<double>(k) / static_cast<double>(count - 1);
    values[static_cast<std::size_t>(k)] =
        k == count - 1 ? to : log ? std::exp(std::log(from) + share * (std::log(to) - std::log(from))) : from + share * (to - from);
  }
  return values;
}

Distribution read_distribution(TomlTable& entry) {
  const std::string kind = entry.choice("distribution", "uniform", {"uniform", "normal", "lognormal"});
  const auto required = [&](const char* a, const char* b) {
    for (const char* key : {a, b}) {
      if (!entry.has(key)) entry.fail(key, "missing: a " + kind + " distribution needs " + a + " and " + b);
    }
  };
  const Range any{-kInfinity, kInfinity, true, true};
  const Range positive{0.0, kInfinity, true, true};
  Distribution d;
  if (kind == "uniform") {
    required("low", "high");
    d = {DistributionKind::uniform, entry.number("low", 0.0, any, ""), entry.number("high", 0.0, any, "")};
    if (!(d.first < d.second)) entry.fail("high", "not above low: expected low < high");
  } else if (kind == "normal") {
    required("mean", "std");
    d = {DistributionKind::normal, entry.number("mean", 0.0, any, ""), entry.number("std", 0.0, positive, "")};
  } else {
    required("median", "sigma");
    d = {DistributionKind::lognormal, entry.number("median", 0.0, positive, ""), entry.number("sigma", 0.0, positive, "")};
  }
  return d;
}

Variation read_variation(const toml::table& table, const std::string& source, std::size_t index) {
  const std::string path = "vary[" + std::to_string(index) + "]";
  reject_unknown_keys(table, source, path,
                      {"key", "values", "from", "to", "count", "spacing", "distribution", "low", "high", "mean", "std",
                       "median", "sigma"});
  TomlTable entry(table, source, path);
  Variation v;
  if (!entry.has("key")) entry.fail("key", "missing: expected a scenario key, e.g. key = \"pools[1].manning_n\"");
  v.key = entry.string("key", "");
  v.line = line_of(table, "key");
  if (v.key.empty() || v.key.find_first_of(" \t\"'=#\n") != std::string::npos) {
    entry.fail_value("key", v.key, "expected a scenario key such as \"pools[1].manning_n\" or \"experiment.operating_opening_mm\"");
  }
  const bool list = entry.has("values");
  const bool range = entry.has("from") || entry.has("to") || entry.has("count");
  const bool drawn = entry.has("distribution");
  if (list + range + drawn != 1) {
    entry.fail("", "expected one of values = [...], from/to/count, or distribution = \"uniform\"|\"normal\"|\"lognormal\"");
  }
  const auto only_with = [&](std::initializer_list<const char*> keys, bool allowed, const std::string& owner) {
    for (const char* key : keys) {
      if (entry.has(key) && !allowed) entry.fail(key, "belongs to " + owner + ": expected it only there");
    }
  };
  only_with({"spacing"}, range, "a from/to/count range");
  if (drawn) {
    const std::string kind = entry.string("distribution", "");
    only_with({"low", "high"}, kind == "uniform", "distribution = \"uniform\"");
    only_with({"mean", "std"}, kind == "normal", "distribution = \"normal\"");
    only_with({"median", "sigma"}, kind == "lognormal", "distribution = \"lognormal\"");
    v.distribution = read_distribution(entry);
    v.logarithmic = v.distribution->kind == DistributionKind::lognormal;
  } else {
    only_with({"low", "high", "mean", "std", "median", "sigma"}, false, "a distribution");
    if (list) {
      v.grid = grid_from_list(table, source, path, v.grid_lines);
    } else {
      v.grid = grid_from_range(entry);
      v.grid_lines.assign(v.grid.size(), line_of(table, "to"));
      v.grid_lines.front() = line_of(table, "from");
    }
    v.logarithmic = range && entry.string("spacing", "linear") == "log";
  }
  return v;
}

void read_variations(const toml::table& root, const std::string& source, SweepFile& f) {
  const toml::node* node = root.get("vary");
  const toml::array* array = node ? node->as_array() : nullptr;
  if (node && (!array || !array->is_array_of_tables())) {
    throw InputError(where(source, *node) + ": vary: expected [[vary]] tables, one per key");
  }
  if (!array || array->empty()) {
    throw InputError(source + ":1: vary: missing: expected at least one [[vary]] table naming a key and its values");
  }
  for (std::size_t i = 0; i < array->size(); ++i) {
    const toml::table& table = *array->get(i)->as_table();
    Variation v = read_variation(table, source, i);
    for (const auto& earlier : f.vary) {
      if (earlier.key == v.key) {
        throw InputError(source + ":" + std::to_string(v.line) + ": vary[" + std::to_string(i) + "].key = " +
                         format_excerpt(v.key) + ": already varied at line " + std::to_string(earlier.line) +
                         ": expected each key once");
      }
    }
    f.vary.push_back(std::move(v));
  }
}

// ---- [compute] --------------------------------------------------------------------------------

Computations read_computations(const toml::table& root, const std::string& source) {
  Computations c;
  const toml::node* node = root.get("compute");
  if (!node) return c;
  const toml::table* table = node->as_table();
  if (!table) throw InputError(where(source, *node) + ": compute: expected a [compute] table");
  reject_unknown_keys(*table, source, "compute", {"summary", "fit", "linearize", "diagnose"});
  TomlTable compute(*table, source, "compute");
  c.summary = compute.boolean("summary", c.summary);
  c.linearize = compute.boolean("linearize", c.linearize);
  c.diagnose = compute.boolean("diagnose", c.diagnose);
  std::string models;
  for (const auto kind : reduced::all_model_kinds()) {
    if (!models.empty()) models += ", ";
    models += reduced::model_name(kind);
  }
  const auto names = read_strings(*table, source, "compute", "fit", "reduced model names", [&](const std::string& name, const std::string& line) {
    if (!reduced::parse_model_kind(name)) {
      throw InputError(line + ": compute.fit: \"" + format_excerpt(name) + "\" is not a reduced model: expected one of " + models);
    }
  });
  for (const auto& name : names) {
    const reduced::ModelKind kind = *reduced::parse_model_kind(name);
    if (std::find(c.fit.begin(), c.fit.end(), kind) != c.fit.end()) {
      compute.fail("fit", "model " + reduced::model_name(kind) + " listed twice: expected each once");
    }
    c.fit.push_back(kind);
  }
  if (!c.summary && c.fit.empty() && !c.linearize && !c.diagnose) {
    compute.fail("", "nothing to compute: expected summary = true, fit = [...], linearize = true or diagnose = true");
  }
  return c;
}

// ---- checks across the file -------------------------------------------------------------------

void read_draws_and_seed(TomlTable& top, SweepFile& f) {
  const auto drawn = std::find_if(f.vary.begin(), f.vary.end(), [](const Variation& v) { return !v.is_grid(); });
  if (top.has("seed")) f.seed = top.seed("seed", 0);
  if (top.has("draws")) {
    f.draws = top.integer("draws", 1, 1, kMaxDraws);
    if (drawn == f.vary.end()) top.fail("draws", "without a distribution: expected draws only when a [[vary]] key has one");
  }
  if (drawn != f.vary.end() && !f.seed) {
    throw InputError(f.source + ":" + std::to_string(drawn->line) + ": vary[" + std::to_string(drawn - f.vary.begin()) +
                     "].distribution: a drawn key needs a seed: expected seed = N (an integer >= 0) at the top of the file");
  }
  if (drawn == f.vary.end() && f.seed) top.fail("seed", "without a distribution: expected seed only when a [[vary]] key has one");
}

void check_case_count(TomlTable& top, const SweepFile& f) {
  double cases = static_cast<double>(f.draws) * static_cast<double>(f.experiments.size());
  for (const auto& v : f.vary) cases *= v.is_grid() ? static_cast<double>(v.grid.size()) : 1.0;
  if (cases > kMaxCases) {
    top.fail("vary", std::to_string(static_cast<long long>(cases)) + " cases: expected at most " +
                         std::to_string(static_cast<long long>(kMaxCases)) + " (fewer values, draws or experiments)");
  }
}

// The scenario takes every key: the first point's values on every experiment, and every grid
// value at the first point, are written into the base scenario and parsed, so that a misspelt
// key or a value out of the key's range stops the sweep before its first case.
void check_scenario_keys(const SweepFile& f) {
  const auto refuse = [&](std::size_t k, double value, int line, const std::exception& e) {
    throw InputError(f.source + ":" + std::to_string(line) + ": vary[" + std::to_string(k) + "].key = " +
                     format_excerpt(f.vary[k].key) + " = " + exact_number(value) +
                     ": expected a key and value the scenario takes (" + e.what() + ")");
  };
  // A refused first point is blamed on the first key whose edit, added to those before it, is
  // refused, at the key's line.
  for (std::size_t e = 0; e < f.experiments.size(); ++e) {
    const Case c = case_at(f, e);
    for (std::size_t k = 0; k < f.vary.size(); ++k) {
      Case alone = c;
      alone.values.resize(k + 1);
      try {
        case_scenario(f, alone);
      } catch (const InputError& error) {
        refuse(k, c.values[k], f.vary[k].line, error);
      }
    }
  }
  // Another grid value refused is blamed on the line it was written on.
  const Case first = case_at(f, 0);
  for (std::size_t k = 0; k < f.vary.size(); ++k) {
    for (std::size_t i = 0; i < f.vary[k].grid.size(); ++i) {
      Case c = first;
      c.values[k] = f.vary[k].grid[i];
      try {
        case_scenario(f, c);
      } catch (const InputError& error) {
        refuse(k, c.values[k], f.vary[k].grid_lines[i], error);
      }
    }
  }
}

}  // namespace

SweepFile parse_sweep_file(const std::string& text, const std::string& source, const std::filesystem::path& folder) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(source + ":" + std::to_string(e.source().begin.line) + ": not valid TOML (" +
                     std::string(e.description()) + "): expected key = value lines and [tables], see docs/sweep.md");
  }
  reject_unknown_keys(root, source, "", {"scenario", "experiments", "seed", "draws", "duration_s", "vary", "compute"});
  TomlTable top(root, source, "");
  SweepFile f;
  f.source = source;
  f.text = text;
  read_base_scenario(top, folder, f);
  const scenarios::Scenario base = scenarios::parse_scenario(f.scenario_text, f.scenario_source);
  read_experiments(root, source, base, f);
  if (top.has("duration_s")) f.duration_s = top.number("duration_s", 0.0, Range{0.0, 1e7, true, false}, "s");
  read_variations(root, source, f);
  read_draws_and_seed(top, f);
  f.compute = read_computations(root, source);
  check_case_count(top, f);
  check_scenario_keys(f);
  return f;
}

SweepFile read_sweep_file(const std::filesystem::path& file) {
  const std::string text = read_text_file(file, "sweep file");
  return parse_sweep_file(text, file.string(), file.has_parent_path() ? file.parent_path() : std::filesystem::path("."));
}

}  // namespace canalsim::sweep
