// The command line of canalsim as one function, so that the program (main.cpp) and the fuzz
// target of the argument layer (fuzz/cli_arguments_fuzz.cpp) run exactly the same parsing and
// error reporting.
#pragma once

#include <CLI/CLI.hpp>

namespace canalsim::cli {

// Registers every subcommand on `app` (cli/commands.hpp).
void add_all_commands(CLI::App& app);

// Parses argv and runs the chosen subcommand. Every error is one line on stderr,
// "canalsim: error: ...", and exit status 1; --help prints and returns 0.
int run_command_line(CLI::App& app, int argc, char** argv);

}  // namespace canalsim::cli
