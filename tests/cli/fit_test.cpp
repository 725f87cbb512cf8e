// `canalsim fit`: an unwritable --json is refused before any recording is read or fitted; the
// uncertainty index of a parameter whose nominal value is 0 is printed as undefined, not inf%.
#include <gtest/gtest.h>

#include "testing/cli_run.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Fit, JsonInAMissingDirectoryIsRefusedBeforeTheRecordingsAreRead) {
  const fs::path scratch = scratch_dir("fit_json");
  // missing.csv would be the error if the recordings were read first.
  const RunResult r = run_canalsim("fit --model liom missing.csv --json nodir/fit.json", scratch);
  EXPECT_TRUE(is_one_error_line(r)) << r.code << ": " << r.err;
  EXPECT_NE(r.err.find("--json nodir/fit.json: directory nodir does not exist"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch / "nodir"));
  fs::remove_all(scratch);
}

// dp (eq. 22) divides by the nominal value. On the simulated lab's op1 and op2 the γ sweep puts
// the nominal NLFOM-S at γ = 0 (as every run of the study does), so its dp is undefined.
TEST(Fit, UncertaintyIndexOfAZeroNominalParameterIsUndefinedNotInfinite) {
  const fs::path scratch = scratch_dir("fit_dp");
  for (const std::string e : {"op1", "op2"}) {
    ASSERT_EQ(run_canalsim("simulate lab -e " + e + " -o " + e + ".csv", scratch).code, 0);
  }
  const RunResult r = run_canalsim("fit --model nlfom-s op1.csv op2.csv --nominal --gamma 0:1:0.5", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find("inf%"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("nan%"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("gamma undefined (nominal 0)"), std::string::npos) << r.out;
  fs::remove_all(scratch);
}

}  // namespace
