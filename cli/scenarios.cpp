// `canalsim scenarios`: lists the built-in scenarios with their experiments; `--show NAME` prints
// one as TOML so that it can be copied to a file, edited and run with `canalsim simulate`.
#include <iostream>

#include "cli/commands.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/scenario_toml.hpp"

namespace canalsim::cli {

void add_scenarios_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("scenarios", "List the built-in scenarios, or print one as TOML");
  auto show = std::make_shared<std::string>();
  cmd->add_option("--show", *show, "Print the built-in scenario NAME as TOML (redirect it to a file to edit it)");
  cmd->callback([show] {
    if (!show->empty()) {
      scenarios::builtin_scenario(*show);  // validates the name, with the list of names on error
      for (const auto& b : scenarios::builtin_scenarios()) {
        if (b.name == *show) std::cout << b.toml;
      }
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
