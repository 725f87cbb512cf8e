// Built-in scenarios, shipped inside the program as TOML text (scenarios/builtin/*.toml) so that
// `canalsim scenarios --show NAME > my.toml` gives a file the user can edit and run.
#pragma once

#include <string>
#include <vector>

#include "scenarios/scenario.hpp"

namespace canalsim::scenarios {

struct BuiltinScenario {
  std::string name;
  std::string toml;
};

const std::vector<BuiltinScenario>& builtin_scenarios();

// The built-in scenario called `name`; throws InputError listing the built-in names.
Scenario builtin_scenario(const std::string& name);

// A built-in name or a path to a TOML file.
Scenario load_scenario_or_builtin(const std::string& name_or_path);

// The TOML text load_scenario_or_builtin reads: the built-in's (built-in names first), or the
// file's. Throws InputError as load_scenario_or_builtin does.
std::string scenario_toml_text(const std::string& name_or_path);

}  // namespace canalsim::scenarios
