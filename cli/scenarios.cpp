// `canalsim scenarios`: lists the built-in scenarios with their experiments; `--show NAME` prints
// one as TOML so that it can be copied to a file, edited and run with `canalsim simulate`.
#include <iostream>

#include "cli/commands.hpp"
#include "scenarios/builtin.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario_toml.hpp"

namespace canalsim::cli {
namespace {

// --show prints only built-in scenarios (a file is already there to read), so the message lists
// just their names — the library's own error also offers "a path to a .toml file".
const scenarios::BuiltinScenario& require_builtin(const std::string& name) {
  std::string names;
  for (const auto& b : scenarios::builtin_scenarios()) {
    if (b.name == name) return b;
    names += (names.empty() ? "" : ", ") + b.name;
  }
  throw InputError("--show " + name + ": expected the name of a built-in scenario: " + names);
}

}  // namespace

void add_scenarios_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenarios", "List the built-in scenarios, or print one as TOML");
  auto show = std::make_shared<std::string>();
  cmd->add_option("--show", *show, "Print the built-in scenario NAME as TOML (redirect it to a file to edit it)");
  cmd->callback([show] {
    if (!show->empty()) {
      std::cout << require_builtin(*show).toml;
      return;
    }
    for (const auto& b : scenarios::builtin_scenarios()) {
      const scenarios::Scenario s = scenarios::parse_scenario(b.toml, "builtin:" + b.name);
      std::cout << b.name << " — " << s.description << "\n  experiments:";
      for (const auto& e : s.experiments) std::cout << ' ' << e.name;
      std::cout << '\n';
    }
  });
}

}  // namespace canalsim::cli
