// Reading scenarios from TOML (docs/scenarios.md) and writing them back, so a user can copy a
// built-in scenario to a file, edit it and run it.
#pragma once

#include <filesystem>
#include <string>

#include "scenarios/scenario.hpp"

namespace canalsim::scenarios {

// Parses and validates a scenario. Throws InputError "FILE:LINE: key: problem, expected ...",
// for syntax errors, unknown keys, wrong types, values out of range and inconsistent settings
// (a gate opening above its maximum or the canal wall, a sensor outside its pool, ...).
Scenario parse_scenario(const std::string& toml_text, const std::string& source);
Scenario load_scenario(const std::filesystem::path& file);

// Cross-field checks (also run by parse_scenario); throws InputError naming the key.
void validate(const Scenario& scenario);

}  // namespace canalsim::scenarios
