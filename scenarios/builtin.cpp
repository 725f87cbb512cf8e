#include "scenarios/builtin.hpp"

#include <filesystem>

#include "core/files.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario_toml.hpp"

namespace canalsim::scenarios {

// Defined in the generated builtin_data.cpp (scenarios/CMakeLists.txt embeds builtin/*.toml).
extern const std::vector<BuiltinScenario> kBuiltinScenarios;

const std::vector<BuiltinScenario>& builtin_scenarios() { return kBuiltinScenarios; }

Scenario builtin_scenario(const std::string& name) {
  std::string names;
  for (const auto& b : builtin_scenarios()) {
    if (b.name == name) return parse_scenario(b.toml, "builtin:" + b.name);
    names += (names.empty() ? "" : ", ") + b.name;
  }
  throw InputError("unknown built-in scenario '" + name + "': expected one of " + names +
                   " or a path to a .toml file");
}

Scenario load_scenario_or_builtin(const std::string& name_or_path) {
  for (const auto& b : builtin_scenarios()) {
    if (b.name == name_or_path) return builtin_scenario(name_or_path);
  }
  if (!std::filesystem::exists(name_or_path)) {
    std::string names;
    for (const auto& b : builtin_scenarios()) names += (names.empty() ? "" : ", ") + b.name;
    throw InputError(name_or_path + ": no such scenario file (built-in scenarios: " + names + ")");
  }
  return load_scenario(name_or_path);
}

std::string scenario_toml_text(const std::string& name_or_path) {
  for (const auto& b : builtin_scenarios()) {
    if (b.name == name_or_path) return b.toml;
  }
  if (!std::filesystem::exists(name_or_path)) load_scenario_or_builtin(name_or_path);  // throws, listing the built-ins
  return read_text_file(name_or_path, "scenario file");
}

}  // namespace canalsim::scenarios
