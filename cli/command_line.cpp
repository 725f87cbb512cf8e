// The command line: subcommand registration, parsing and the one-line error contract.
#include <chrono>
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <thread>

#include "cli/command_line.hpp"
#include "cli/commands.hpp"
#include "cluster/distribute.hpp"
#include "core/errors.hpp"

namespace {

// The contract is one line per error; a message that spans lines (a library joining several
// problems) is folded rather than letting the second line look like a separate error.
std::string one_line(std::string message) {
  while (!message.empty() && message.back() == '\n') message.pop_back();
  for (std::string::size_type at = message.find('\n'); at != std::string::npos; at = message.find('\n', at)) {
    message.replace(at, 1, "; ");
  }
  // The last guard against a huge value echoed somewhere (a 1 MB field): an error line stays short.
  constexpr std::string::size_type kLongest = 2000;
  if (message.size() > kLongest) message = message.substr(0, kLongest) + "... (message cut)";
  return message;
}

std::string subcommand_list(const CLI::App& app) {
  std::string names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
  }
  return names;
}

// Before a subcommand is recognised CLI11 only knows that one is missing ("A subcommand is
// required", even for `canalsim foo`); say what was typed instead and list what exists.
std::string top_level_problem(const CLI::App& app, int argc, char** argv) {
  const std::string expected = "expected a subcommand: " + subcommand_list(app) + " (see canalsim --help)";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.empty() || arg[0] != '-') return "unknown subcommand '" + arg + "'; " + expected;
  }
  if (argc > 1) return "unknown option '" + std::string(argv[1]) + "'; " + expected;
  return "no subcommand given; " + expected;
}

// CLI11 prints its errors on two lines ("... Run with --help ...") and exits with its own codes
// (105, 106, 109); canalsim errors are one line "canalsim: error: ..." and exit status 1. Help
// requests still print the help and exit 0; RuntimeError carries a subcommand's own exit status
// after it has printed its error.
int report_parse_error(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  if (e.get_exit_code() == 0 || e.get_name() == "RuntimeError") return app.exit(e);
  const auto chosen = app.get_subcommands();
  std::string message = e.what();
  if (chosen.empty()) {
    message = top_level_problem(app, argc, argv);
  } else if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
    const std::string sub = chosen.front()->get_name();
    const std::string::size_type colon = message.find(": ");
    const std::string extras = colon == std::string::npos ? message : message.substr(colon + 2);
    message = "unexpected argument(s) for canalsim " + sub + ": " + extras + " (see canalsim " + sub + " --help)";
  }
  std::cerr << "canalsim: error: " << one_line(message) << '\n';
  return 1;
}

}  // namespace

namespace canalsim::cli {
namespace {

// An empty value (`--json ""`, `-o ""`) would read as the option not given, or fail after the work
// naming no file: every option that takes a value refuses it as it is parsed.
void refuse_empty_values(CLI::App& app) {
  const CLI::Validator non_empty(
      [](std::string& text) -> std::string { return text.empty() ? "expected a value, got an empty string" : ""; },
      "");
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    for (CLI::Option* option : sub->get_options()) {
      if (option->get_items_expected_min() > 0) option->check(non_empty);
    }
  }
}

// Under mpirun every process runs the command line: only the commands that share their work out
// (cluster/distribute.hpp) may, or each process would write the same outputs.
void refuse_several_processes_unless_distributed(int argc, char** argv) {
  if (cluster::processes() == 1) return;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word.front() == '-') continue;
    if (word == "sweep" || word == "blindtest") return;
    throw InputError("canalsim " + word + " runs on one process, not " + std::to_string(cluster::processes()) +
                     ": expected mpirun only with sweep or blindtest");
  }
}

// An error in an MPI job: the other processes may be waiting for this one, so the job stops.
// An error met by every process (a bad input) is printed once, by rank 0: the others wait a
// second, and are stopped by rank 0's abort before they print.
[[noreturn]] void stop_the_job(const std::string& message) {
  if (cluster::is_root()) cluster::abort_job(one_line(message));
  std::this_thread::sleep_for(std::chrono::seconds(1));
  cluster::abort_job("rank " + std::to_string(cluster::rank()) + ": " + one_line(message));
}

}  // namespace

void add_all_commands(CLI::App& app) {
  app.name("canalsim");  // usage lines name the program, not the path it was started by
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Print help for every subcommand");
  add_version_command(app);
  add_dambreak_command(app);
  add_prbs_command(app);
  add_fit_command(app);
  add_resample_command(app);
  add_reproduce_command(app);
  add_scenarios_command(app);
  add_simulate_command(app);
  add_calibrate_command(app);
  add_diagnose_command(app);
  add_blindtest_command(app);
  add_linearize_command(app);
  add_sweep_command(app);
  refuse_empty_values(app);
}

int run_command_line(CLI::App& app, int argc, char** argv) {
  try {
    refuse_several_processes_unless_distributed(argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return report_parse_error(app, e, argc, argv);
  } catch (const std::bad_alloc&) {
    // What ran out of memory is the subcommand's work on its inputs: say which, and what to do.
    const auto chosen = app.get_subcommands();
    const std::string sub = chosen.empty() ? std::string() : " " + chosen.front()->get_name();
    std::cerr << "canalsim: error: canalsim" << sub << " ran out of memory: expected inputs that fit in memory "
              << "(shorter or coarser recordings, fewer cells)\n";
    return 1;
  } catch (const std::exception& e) {
    if (cluster::processes() > 1) stop_the_job(e.what());
    std::cerr << "canalsim: error: " << one_line(e.what()) << '\n';
    return 1;
  }
  return 0;
}

}  // namespace canalsim::cli
