// `canalsim diagnose` rejects bad arguments and unreadable recordings with one error line and a
// non-zero exit, and writes no output file.
#include <gtest/gtest.h>

#include "testing/cli_run.hpp"

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

// The first problem is reported, naming the file and line; the second file's problem (and the
// "no recordings given" that used to follow from the first) are not printed.
TEST(Diagnose, TwoBadRecordingsGiveOneLineNamingTheFirstFileAndLine) {
  const fs::path scratch = scratch_dir("diagnose_two_bad");
  std::ofstream(scratch / "bad1.csv") << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,abc,45\n";
  std::ofstream(scratch / "bad2.csv") << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,25,45\n";
  const RunResult r = run_canalsim("diagnose --scenario lab bad1.csv bad2.csv --json d.json", scratch);
  EXPECT_TRUE(is_one_error_line(r)) << r.code << ": " << r.err;
  EXPECT_NE(r.err.find("bad1.csv:3"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("bad2.csv"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("no recordings given"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch / "d.json"));
  fs::remove_all(scratch);
}

TEST(Diagnose, ARecordingThatDoesNotFitTheScenarioIsOneLineNamingIt) {
  const fs::path scratch = scratch_dir("diagnose_mismatch");
  std::ofstream(scratch / "short.csv") << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,25,45\n";
  const RunResult r = run_canalsim("diagnose --scenario lab short.csv short.csv", scratch);
  EXPECT_TRUE(is_one_error_line(r)) << r.code << ": " << r.err;
  EXPECT_NE(r.err.find("short.csv: 2 samples, expected at least 50"), std::string::npos) << r.err;
  fs::remove_all(scratch);
}

TEST(Diagnose, OutputsInAMissingDirectoryAreRefusedBeforeTheRecordingsAreRead) {
  const fs::path scratch = scratch_dir("diagnose_outputs");
  for (const std::string flag : {"--json", "--report"}) {
    for (const std::string mode : {"--scenario lab", "--model liom"}) {
      const RunResult r = run_canalsim("diagnose " + mode + " missing.csv " + flag + " nodir/out", scratch);
      EXPECT_TRUE(is_one_error_line(r)) << r.code << ": " << r.err;
      EXPECT_NE(r.err.find(flag + " nodir/out: directory nodir does not exist"), std::string::npos) << r.err;
    }
  }
  EXPECT_EQ(entry_count(scratch), 0u);
  fs::remove_all(scratch);
}

}  // namespace
