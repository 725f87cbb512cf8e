#include "cli/recording_format.hpp"

#include <map>
#include <sstream>
#include <vector>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "core/text.hpp"

namespace canalsim::cli {
namespace {

// canalsim's columns by their short names (the column without its unit suffix) and full names.
const std::map<std::string, std::string>& column_names() {
  static const std::map<std::string, std::string> names = {
      {"t", columns::time},           {"u", columns::gate_command},          {"x_up", columns::gate_position},
      {"y_up", columns::upstream_level}, {"y_dw", columns::level_below_gate}, {"y_dwe", columns::level_downstream_end},
      {"q", columns::discharge}};
  return names;
}

// "NAME=VALUE,NAME=VALUE" as pairs; a malformed item is an error naming the flag.
std::vector<std::pair<std::string, std::string>> pairs(const std::string& text, const std::string& flag,
                                                      const std::string& expected) {
  std::vector<std::pair<std::string, std::string>> out;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto eq = item.find('=');
    const std::string name = trim(item.substr(0, eq)), value = eq == std::string::npos ? "" : trim(item.substr(eq + 1));
    if (eq == std::string::npos || name.empty() || value.empty()) {
      throw InputError(flag + " " + format_excerpt(item) + ": expected " + expected);
    }
    out.emplace_back(name, value);
  }
  return out;
}

std::map<std::string, std::string> parse_columns(const std::string& text) {
  const std::string expected = "NAME=COLUMN with NAME one of t, u, x_up, y_up, y_dw, y_dwe, q (or t_s, u_mm, ...)";
  std::map<std::string, std::string> out;
  for (const auto& [name, column] : pairs(text, "--columns", expected)) {
    std::string ours;
    for (const auto& [short_name, full_name] : column_names()) {
      if (name == short_name || name == full_name) ours = full_name;
    }
    if (ours.empty()) throw InputError("--columns " + format_excerpt(name + "=" + column) + ": expected " + expected);
    if (!out.emplace(ours, column).second) throw InputError("--columns: " + ours + " is named twice");
  }
  return out;
}

std::map<std::string, std::string> parse_units(const std::string& text) {
  const std::string expected = "u=UNIT or y=UNIT with UNIT one of mm, cm, m";
  std::map<std::string, std::string> out;
  for (const auto& [which, unit] : pairs(text, "--units", expected)) {
    if ((which != "u" && which != "y") || (unit != "mm" && unit != "cm" && unit != "m")) {
      throw InputError("--units " + format_excerpt(which + "=" + unit) + ": expected " + expected);
    }
    if (!out.emplace(which, unit).second) throw InputError("--units: " + which + " is given twice");
  }
  return out;
}

}  // namespace

void RecordingFormat::add_options(CLI::App* command) {
  command->add_option("--columns", columns,
                      "The recordings' own column names, e.g. t=time,u=gate,y_dwe=level (canalsim's t, u, x_up, "
                      "y_up, y_dw, y_dwe, q = the file's)");
  command->add_option("--units", units,
                      "Units of recordings whose metadata declare none, e.g. u=m,y=cm (u: command and gate "
                      "position, y: levels; mm, cm or m)");
}

Recording RecordingFormat::read(const std::string& file, RecordingReadOptions options) const {
  options.column_names = parse_columns(columns);
  const std::map<std::string, std::string> declared = parse_units(units);
  Recording recording = read_recording(file, options);
  for (const auto& [which, unit] : declared) {
    const std::string key = which + "_unit";
    const std::string own = recording.meta(key);
    if (!own.empty() && own != unit) {
      throw InputError(recording.source + ": --units " + which + "=" + unit + ", but the file declares # " + key + ": " +
                       own + " (expected one of them)");
    }
    recording.set_meta(key, unit);
  }
  return recording;
}

}  // namespace canalsim::cli
