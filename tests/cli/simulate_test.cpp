// `canalsim simulate`: --out-dir creates the directory it is given; argument problems (a path that
// cannot be a directory, -o together with --out-dir, two experiments that map to one file name,
// an -o file in a missing directory) are one error line before anything is simulated.
#include <gtest/gtest.h>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

// The built-in lab canal with two 2-second experiments at a constant opening, so that a test
// simulates in a fraction of a second. "a*" and "as" both map to the file name as.csv.
fs::path write_short_lab(const fs::path& scratch) {
  const RunResult shown = run_canalsim("scenarios --show lab", scratch);
  EXPECT_EQ(shown.code, 0) << shown.err;
  const std::string canal = shown.out.substr(0, shown.out.find("[[experiments]]"));
  const fs::path file = scratch / "short.toml";
  std::ofstream(file) << canal << R"([[experiments]]
name = "a*"
operating_opening_mm = 15
duration_s = 2
[experiments.input]
kind = "constant"

[[experiments]]
name = "as"
operating_opening_mm = 25
duration_s = 2
[experiments.input]
kind = "constant"

[[experiments]]
name = "b"
operating_opening_mm = 20
duration_s = 2
[experiments.input]
kind = "constant"
)";
  return file;
}

TEST(Simulate, OutDirIsCreatedWithItsParentsAndStarIsWrittenAsS) {
  const fs::path scratch = scratch_dir("simulate_create");
  write_short_lab(scratch);
  const RunResult r = run_canalsim("simulate short.toml -e 'a*' -e b --out-dir recs/new", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(scratch / "recs" / "new" / "as.csv"));
  EXPECT_TRUE(fs::is_regular_file(scratch / "recs" / "new" / "b.csv"));
  fs::remove_all(scratch);
}

TEST(Simulate, AnOutDirThatIsAFileIsOneErrorLineAndTheFileIsKept) {
  const fs::path scratch = scratch_dir("simulate_file");
  write_short_lab(scratch);
  std::ofstream(scratch / "taken") << "keep me\n";
  for (const std::string dir : {"taken", "taken/sub"}) {
    const std::size_t before = entry_count(scratch);
    const RunResult r = run_canalsim("simulate short.toml -e b --out-dir " + dir, scratch);
    EXPECT_TRUE(fails_naming(r, "--out-dir " + dir + ": taken exists and is not a directory"));
    EXPECT_EQ(entry_count(scratch), before);
  }
  EXPECT_EQ(read_text(scratch / "taken"), "keep me\n");
  fs::remove_all(scratch);
}

TEST(Simulate, OutputFileAndOutDirTogetherAreRefused) {
  const fs::path scratch = scratch_dir("simulate_both");
  write_short_lab(scratch);
  expect_refused_writing_nothing(scratch, "simulate short.toml -e b -o b.csv --out-dir recs",
                                 "-o b.csv and --out-dir recs", {"b.csv", "recs"});
  fs::remove_all(scratch);
}

TEST(Simulate, ExperimentsWithTheSameFileNameAreRefusedBeforeAnyIsSimulated) {
  const fs::path scratch = scratch_dir("simulate_collide");
  write_short_lab(scratch);
  const RunResult r = run_canalsim("simulate short.toml --out-dir recs", scratch);
  EXPECT_TRUE(fails_naming(r, "'a*' and 'as'"));
  EXPECT_NE(r.err.find("recs/as.csv"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");  // no "wrote ..." line
  EXPECT_FALSE(fs::exists(scratch / "recs"));
  fs::remove_all(scratch);
}

TEST(Simulate, AnOutputFileInAMissingDirectoryIsRefused) {
  const fs::path scratch = scratch_dir("simulate_missing");
  write_short_lab(scratch);
  expect_refused_writing_nothing(scratch, "simulate short.toml -e b -o nodir/b.csv",
                                 "-o nodir/b.csv: directory nodir does not exist", {"nodir"});
  fs::remove_all(scratch);
}

TEST(Simulate, TheSecondSimulatorWritesARecordingOfItsOwnAndRefusesACanalItDoesNotSimulate) {
  const fs::path scratch = scratch_dir("simulate_staggered");
  write_short_lab(scratch);
  const RunResult r = run_canalsim("simulate short.toml -e b --scheme staggered --staggered-cells 50 -o b.csv", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  const std::string text = read_text(scratch / "b.csv");
  EXPECT_NE(text.find("# generator: canalsim staggered simulator (Stelling & Duinmeijer 2003) on 50 cells"),
            std::string::npos) << text.substr(0, 400);
  EXPECT_NE(text.find("t_s,u_mm,x_up_mm,y_up_mm,y_dw_mm,y_dwe_mm,q_lps,regime"), std::string::npos);
  // The ASCE canals have several pools: one line naming the key, and no file.
  expect_refused_writing_nothing(scratch, "simulate asce1 -e steady --scheme staggered -o a.csv",
                                 "the staggered simulator takes one pool", {"a.csv"});
  fs::remove_all(scratch);
}

}  // namespace
