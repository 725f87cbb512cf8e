// `canalsim reproduce --out DIR` refuses an output directory it cannot create before doing any
// work: one error line, a non-zero exit, nothing written.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

struct RunResult {
  int status = 0;
  std::string err;
};

RunResult run_canalsim(const std::string& arguments, const fs::path& scratch) {
  const fs::path err = scratch / "stderr.txt";
  const std::string command = std::string(CANALSIM_PROGRAM) + " " + arguments + " > /dev/null 2> " + err.string();
  RunResult r;
  r.status = std::system(command.c_str());
  std::ifstream in(err);
  std::stringstream text;
  text << in.rdbuf();
  r.err = text.str();
  return r;
}

fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("canalsim_cli_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n' ? 1 : 0;
  return n;
}

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
