// canalsim: command-line entry point. Errors are one line on stderr and a non-zero exit.
#include <exception>
#include <iostream>

#include "cli/commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"canalsim — Saint-Venant canal simulation, fractional-order reduced models and "
               "model-mismatch diagnosis"};
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Print help for every subcommand");
  canalsim::cli::add_version_command(app);
#ifdef CANALSIM_HAVE_DAMBREAK
  canalsim::cli::add_dambreak_command(app);
#endif
#ifdef CANALSIM_HAVE_PRBS
  canalsim::cli::add_prbs_command(app);
#endif
#ifdef CANALSIM_HAVE_FIT
  canalsim::cli::add_fit_command(app);
#endif
#ifdef CANALSIM_HAVE_REPRODUCE
  canalsim::cli::add_reproduce_command(app);
#endif
  canalsim::cli::add_scenarios_command(app);
  canalsim::cli::add_simulate_command(app);
#ifdef CANALSIM_HAVE_DIAGNOSE
  canalsim::cli::add_diagnose_command(app);
  canalsim::cli::add_blindtest_command(app);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "canalsim: error: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
