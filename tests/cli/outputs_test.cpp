// The smaller subcommands (blindtest, prbs, dambreak, scenarios, version): output paths are
// checked before the work, messages say only what is accepted, printed figures are exact.
#include <gtest/gtest.h>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

// blindtest runs for minutes before writing --json; the check must come first (this test would
// time out otherwise).
TEST(Outputs, EveryFileFlagRefusesAMissingDirectoryWithOneLine) {
  const fs::path scratch = scratch_dir("outputs_missing");
  for (const std::string args : {"blindtest --json nodir/out", "prbs -o nodir/out", "dambreak -o nodir/out"}) {
    const RunResult r = run_canalsim(args, scratch);
    EXPECT_TRUE(fails_naming(r, "nodir/out: directory nodir does not exist")) << args;
    EXPECT_EQ(r.out, "") << args;
  }
  EXPECT_EQ(entry_count(scratch), 0u);
  fs::remove_all(scratch);
}

TEST(Outputs, AnOutputFileThatIsADirectoryIsRefused) {
  const fs::path scratch = scratch_dir("outputs_dir");
  fs::create_directory(scratch / "d");
  const RunResult r = run_canalsim("dambreak -o d", scratch);
  EXPECT_TRUE(fails_naming(r, "-o d: is a directory"));
  EXPECT_EQ(entry_count(scratch), 1u);
  fs::remove_all(scratch);
}

TEST(Outputs, ScenariosShowListsOnlyBuiltInNames) {
  const fs::path scratch = scratch_dir("outputs_show");
  const RunResult r = run_canalsim("scenarios --show lab.toml", scratch);
  EXPECT_TRUE(is_one_error_line(r)) << r.code << ": " << r.err;
  EXPECT_NE(r.err.find("--show lab.toml: expected the name of a built-in scenario: asce1, asce2, lab"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find(".toml file"), std::string::npos) << r.err;
  fs::remove_all(scratch);
}

// N Tc = (2^20 - 1) x 0.5 s = 524287.5 s exactly; six significant digits printed 524288.
TEST(Outputs, PrbsPrintsThePeriodExactly) {
  const fs::path scratch = scratch_dir("outputs_prbs");
  const RunResult r = run_canalsim("prbs --stages 20", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("period T = N Tc          524287.5 s"), std::string::npos) << r.out;
  fs::remove_all(scratch);
}

TEST(Outputs, VersionNamesTheLibrariesItWasBuiltWith) {
  const fs::path scratch = scratch_dir("outputs_version");
  const RunResult r = run_canalsim("version", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* library : {"Eigen ", "SUNDIALS ", "SuiteSparse ", "KLU ", "toml++ ", "nlohmann_json ", "CLI11 ", "MPI: "}) {
    EXPECT_NE(r.out.find(library), std::string::npos) << library << " missing from\n" << r.out;
  }
  fs::remove_all(scratch);
}

}  // namespace
