// `canalsim version`: the program version and the versions of the libraries it was built with.
#include <Eigen/Core>
#include <iostream>
#include <sundials/sundials_config.h>

#include "cli/commands.hpp"

#ifndef CANALSIM_VERSION
#define CANALSIM_VERSION "unknown"
#endif

namespace canalsim::cli {

void add_version_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("version", "Print the canalsim version and its library versions");
  cmd->callback([] {
    std::cout << "canalsim " << CANALSIM_VERSION << "\n"
              << "  Eigen " << EIGEN_WORLD_VERSION << '.' << EIGEN_MAJOR_VERSION << '.'
              << EIGEN_MINOR_VERSION << ", SUNDIALS " << SUNDIALS_VERSION << '\n';
  });
}

}  // namespace canalsim::cli
