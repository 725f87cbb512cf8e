// Subcommands of the canalsim program: one file per subcommand, each registering itself on the
// application. The CLI only parses arguments and calls the libraries (docs/architecture.md).
#pragma once

#include <CLI/CLI.hpp>

namespace canalsim::cli {

void add_version_command(CLI::App& app);
void add_dambreak_command(CLI::App& app);
void add_prbs_command(CLI::App& app);
void add_fit_command(CLI::App& app);
void add_resample_command(CLI::App& app);
void add_scenarios_command(CLI::App& app);
void add_simulate_command(CLI::App& app);
void add_diagnose_command(CLI::App& app);
void add_blindtest_command(CLI::App& app);
void add_reproduce_command(CLI::App& app);
void add_linearize_command(CLI::App& app);
void add_calibrate_command(CLI::App& app);
void add_sweep_command(CLI::App& app);

}  // namespace canalsim::cli
