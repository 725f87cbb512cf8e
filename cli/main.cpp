// canalsim: command-line entry point. Errors are one line on stderr and a non-zero exit
// (cli/command_line.hpp).
#include "cli/command_line.hpp"

int main(int argc, char** argv) {
  CLI::App app{"canalsim — Saint-Venant canal simulation, fractional-order reduced models and "
               "model-mismatch diagnosis"};
  canalsim::cli::add_all_commands(app);
  return canalsim::cli::run_command_line(app, argc, argv);
}
