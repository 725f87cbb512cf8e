// `canalsim reproduce --out DIR` refuses an output directory it cannot create before doing any
// work: one error line, a non-zero exit, nothing written.
#include <gtest/gtest.h>

#include "testing/cli_run.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Reproduce, AMissingParentDirectoryIsOneErrorLineAndWritesNothing) {
  const fs::path scratch = scratch_dir("missing");
  const fs::path out = scratch / "no" / "such" / "dir";
  const RunResult r = run_canalsim("reproduce --out " + out.string(), scratch);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch / "no"));
  fs::remove_all(scratch);
}

TEST(Reproduce, AnOutputPathThatIsAFileIsOneErrorLineAndLeavesTheFileAlone) {
  const fs::path scratch = scratch_dir("file");
  const fs::path out = scratch / "taken";
  std::ofstream(out) << "keep me\n";
  const RunResult r = run_canalsim("reproduce --out " + out.string(), scratch);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("not a directory"), std::string::npos) << r.err;
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "keep me");
  fs::remove_all(scratch);
}

}  // namespace
