// `canalsim version`: the program version and the versions of the libraries it was built with —
// every library whose headers the canalsim target reaches and that states its version in a macro
// (NLopt only reaches the program inside the reduced-models library, so it is not listed).
#include <CLI/Version.hpp>
#include <Eigen/Core>
#include <SuiteSparse_config.h>
#include <iostream>
#include <sstream>
#include <string>
#include <klu.h>
#include <nlohmann/json_fwd.hpp>
#include <sundials/sundials_config.h>
#include <toml++/impl/version.h>  // the version macros only, not the whole parser

#include "cli/commands.hpp"
#include "cluster/distribute.hpp"

#ifndef CANALSIM_VERSION
#define CANALSIM_VERSION "unknown"
#endif

namespace canalsim::cli {

namespace {

// Four lines, without a final newline.
std::string version_text() {
  std::ostringstream out;
  out << "canalsim " << CANALSIM_VERSION << "\n"
      << "  Eigen " << EIGEN_WORLD_VERSION << '.' << EIGEN_MAJOR_VERSION << '.' << EIGEN_MINOR_VERSION
      << ", SUNDIALS " << SUNDIALS_VERSION << ", SuiteSparse " << SUITESPARSE_MAIN_VERSION << '.'
      << SUITESPARSE_SUB_VERSION << '.' << SUITESPARSE_SUBSUB_VERSION << " (KLU " << KLU_MAIN_VERSION << '.'
      << KLU_SUB_VERSION << '.' << KLU_SUBSUB_VERSION << ")\n"
      << "  toml++ " << TOML_LIB_MAJOR << '.' << TOML_LIB_MINOR << '.' << TOML_LIB_PATCH << ", nlohmann_json "
      << NLOHMANN_JSON_VERSION_MAJOR << '.' << NLOHMANN_JSON_VERSION_MINOR << '.' << NLOHMANN_JSON_VERSION_PATCH
      << ", CLI11 " << CLI11_VERSION << "\n"
      << "  MPI: " << (cluster::built_with_mpi() ? cluster::mpi_library_version() : "not built in (one process)");
  return out.str();
}

}  // namespace

void add_version_command(CLI::App& app) {
  // Both spellings: the subcommand, and the flag every command-line tool answers.
  app.set_version_flag("--version", [] { return version_text(); }, "Print the canalsim version and its library versions");
  auto* cmd = app.add_subcommand("version", "Print the canalsim version and its library versions");
  cmd->callback([] { std::cout << version_text() << '\n'; });
}

}  // namespace canalsim::cli
