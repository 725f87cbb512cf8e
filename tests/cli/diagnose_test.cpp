// `canalsim diagnose` rejects bad arguments and unreadable recordings with one error line and a
// non-zero exit, and writes no output file.
#include <gtest/gtest.h>

#include "tests/cli/cli_run.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Diagnose, NeitherOrBothOfScenarioAndModelIsOneErrorLine) {
  const fs::path scratch = scratch_dir("diagnose_choice");
  const fs::path rec = scratch / "rec.csv";
  std::ofstream(rec) << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,25,45\n0.26,25,45.1\n";
  for (const std::string& args : {"diagnose " + rec.string(), "diagnose --scenario lab --model liom " + rec.string()}) {
    const RunResult r = run_canalsim(args, scratch);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("exactly one of --scenario"), std::string::npos) << r.err;
  }
  fs::remove_all(scratch);
}

TEST(Diagnose, AnUnknownModelOrAMissingRecordingIsOneErrorLineAndWritesNoJson) {
  const fs::path scratch = scratch_dir("diagnose_model");
  const fs::path json = scratch / "d.json";
  RunResult r = run_canalsim("diagnose --model nosuch " + (scratch / "x.csv").string() + " --json " + json.string(), scratch);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  r = run_canalsim("diagnose --model liom " + (scratch / "missing.csv").string() + " --json " + json.string(), scratch);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("missing.csv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(json));
  fs::remove_all(scratch);
}

}  // namespace
