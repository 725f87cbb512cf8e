// `canalsim` parse errors — unknown subcommands and options, values outside a flag's range,
// missing files — follow the same contract as every other error: one line "canalsim: error: ..."
// naming the subcommand or flag and what is expected, exit status 1. Help still exits 0.
#include <gtest/gtest.h>

#include <vector>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Main, AnUnknownSubcommandIsNamedAndTheSubcommandsAreListed) {
  const fs::path scratch = scratch_dir("main_unknown");
  const RunResult r = run_canalsim("foo", scratch);
  EXPECT_TRUE(fails_naming(r, "unknown subcommand 'foo'"));
  EXPECT_NE(r.err.find("simulate"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("scenarios"), std::string::npos) << r.err;
  fs::remove_all(scratch);
}

TEST(Main, ParseErrorsAreOneLineNamingTheArgumentWithExitStatusOne) {
  const fs::path scratch = scratch_dir("main_parse");
  const std::vector<ErrorCase> cases = {
      {"", "no subcommand given"},
      {"--bogus", "unknown option '--bogus'"},
      {"fit --model liom x.csv --bogus", "--bogus"},
      {"fit --model liom missing.csv", "missing.csv"},
      {"fit --model liom --threads abc x.csv", "--threads: expected a number of threads from 1 to 64, got abc"},
      {"diagnose --scenario lab --fit-fraction 0.95 x.csv", "--fit-fraction: expected a fraction in [0.11, 0.89], got 0.95"},
      {"blindtest --trials 0", "--trials: expected a number of trials from 1 to 100000, got 0"},
      {"blindtest --duration 5", "--duration: expected a number of seconds >= 20"},
      {"reproduce --gamma-step 0", "--gamma-step: expected a step in [0.001, 10], got 0"},
      {"simulate", "scenario is required"},
  };
  expect_errors(cases, scratch, {"Run with --help"});
  fs::remove_all(scratch);
}

// The values reach library option structs (DataOptions, Actuation, GlOptions); the message must
// name the flag the user typed instead.
TEST(Main, BadFlagValuesNameTheFlagNotTheLibraryField) {
  const fs::path scratch = scratch_dir("main_flags");
  const std::vector<ErrorCase> cases = {
      {"fit --model nlfom-s --upstream-level -5 x.csv", "--upstream-level: expected a level in mm > 0, got -5"},
      {"fit --model liom --gate-speed -3 x.csv", "--gate-speed: expected a speed in mm/s in [0, 1e+06], got -3"},
      {"fit --model liom --quantum -1 x.csv", "--quantum: expected a resolution in mm in [0, 100], got -1"},
      {"fit --model lfom --memory-terms 0 x.csv", "--memory-terms: expected a number of terms"},
      {"diagnose --model nlfom-s --upstream-level 0 x.csv", "--upstream-level: expected a level in mm > 0, got 0"},
  };
  expect_errors(cases, scratch, {"Options.", "Actuation."});
  fs::remove_all(scratch);
}

TEST(Main, EverySubcommandTakesBetweenOneAndSixtyFourThreads) {
  const fs::path scratch = scratch_dir("main_threads");
  for (const std::string sub : {"fit --model liom x.csv", "diagnose --scenario lab x.csv", "blindtest", "reproduce"}) {
    for (const std::string n : {"0", "65"}) {
      const RunResult r = run_canalsim(sub + " --threads " + n, scratch);
      EXPECT_TRUE(fails_naming(r, "--threads: expected a number of threads from 1 to 64, got " + n));
    }
  }
  fs::remove_all(scratch);
}

TEST(Main, HelpPrintsHelpAndExitsZero) {
  const fs::path scratch = scratch_dir("main_help");
  RunResult r = run_canalsim("--help", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("simulate"), std::string::npos) << r.out;
  r = run_canalsim("fit --help", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("--upstream-level"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Usage: canalsim fit "), std::string::npos) << r.out;  // the program, not its path
  fs::remove_all(scratch);
}

// `--version` and `version` print the same lines: the program's version and its libraries'.
TEST(Main, VersionIsAFlagAndASubcommand) {
  const fs::path scratch = scratch_dir("main_version");
  const RunResult flag = run_canalsim("--version", scratch);
  const RunResult sub = run_canalsim("version", scratch);
  EXPECT_EQ(flag.code, 0) << flag.err;
  EXPECT_EQ(sub.code, 0) << sub.err;
  EXPECT_EQ(flag.out.rfind("canalsim ", 0), 0u) << flag.out;
  EXPECT_NE(flag.out.find("Eigen 3."), std::string::npos) << flag.out;
  EXPECT_EQ(flag.out, sub.out);
  fs::remove_all(scratch);
}

}  // namespace
