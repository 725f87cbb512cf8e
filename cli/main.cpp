// canalsim: command-line entry point. Errors are one line on stderr and a non-zero exit
// (cli/command_line.hpp).
#include <exception>
#include <memory>
#include <iostream>

#include "cli/command_line.hpp"
#include "cluster/distribute.hpp"

int main(int argc, char** argv) {
  std::unique_ptr<canalsim::cluster::Session> job;  // MPI, when launched by mpirun
  try {
    job = std::make_unique<canalsim::cluster::Session>();
  } catch (const std::exception& e) {
    std::cerr << "canalsim: error: " << e.what() << '\n';
    return 1;
  }
  CLI::App app{"canalsim — Saint-Venant canal simulation, fractional-order reduced models and "
               "model-mismatch diagnosis"};
  canalsim::cli::add_all_commands(app);
  return canalsim::cli::run_command_line(app, argc, argv);
}
