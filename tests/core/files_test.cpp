// Writing files all or nothing: a set of files either all replace what was there or none does,
// and nothing is left behind — after a failure, and after SIGINT/SIGTERM in the middle.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include "core/errors.hpp"
#include "core/files.hpp"

namespace {

namespace fs = std::filesystem;
using canalsim::InputError;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("canalsim_files_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void put(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(Files, ASetReplacesEveryFileWhenAllSucceed) {
  const fs::path dir = scratch("set_ok");
  put(dir / "a.txt", "old a");
  canalsim::write_files_atomically({{dir / "a.txt", "new a"}, {dir / "b.txt", "new b"}});
  EXPECT_EQ(text_of(dir / "a.txt"), "new a");
  EXPECT_EQ(text_of(dir / "b.txt"), "new b");
  EXPECT_EQ(entries(dir), 2u);  // no temporary or backup left
  fs::remove_all(dir);
}

// The third file cannot be replaced (a directory holds its name): the first two had been
// renamed into place already and must get their previous contents back; the new one must go.
TEST(Files, AFailedSetRestoresWhatWasThere) {
  const fs::path dir = scratch("set_fail");
  put(dir / "tables.json", "old json");
  put(dir / "tables.md", "old md");
  fs::create_directories(dir / "report.html" / "inside");
  EXPECT_THROW(canalsim::write_files_atomically({{dir / "tables.json", "new json"},
                                                  {dir / "new.txt", "new file"},
                                                  {dir / "tables.md", "new md"},
                                                  {dir / "report.html", "html"}}),
               InputError);
  EXPECT_EQ(text_of(dir / "tables.json"), "old json");
  EXPECT_EQ(text_of(dir / "tables.md"), "old md");
  EXPECT_FALSE(fs::exists(dir / "new.txt"));
  EXPECT_TRUE(fs::is_directory(dir / "report.html" / "inside"));
  EXPECT_EQ(entries(dir), 3u) << "temporary or backup files left behind";
  fs::remove_all(dir);
}

TEST(Files, ASetThatCannotBeWrittenTouchesNothing) {
  const fs::path dir = scratch("set_unwritable");
  put(dir / "a.txt", "old a");
  EXPECT_THROW(canalsim::write_files_atomically({{dir / "a.txt", "new a"}, {dir / "missing" / "b.txt", "b"}}),
               InputError);
  EXPECT_EQ(text_of(dir / "a.txt"), "old a");
  EXPECT_EQ(entries(dir), 1u);
  fs::remove_all(dir);
}

// A guarded temporary file in a child process that is then terminated by the signal: the handler
// removes the file and the child still dies of that signal (the exit status a shell expects).
void expect_signal_removes_temporary(int signal_number) {
  const fs::path dir = scratch("signal_" + std::to_string(signal_number));
  const fs::path temporary = dir / "out.csv.tmp.1";
  const fs::path backup = dir / "kept.csv.bak.1", restored = dir / "kept.csv";
  put(restored, "new contents");
  put(backup, "old contents");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    canalsim::InterruptGuard temp_guard(temporary);
    canalsim::InterruptGuard backup_guard(backup, restored);
    put(temporary, "half written");
    ::raise(signal_number);
    ::_exit(0);  // not reached
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status));
  if (WIFSIGNALED(status)) {
    EXPECT_EQ(WTERMSIG(status), signal_number);
  }
  EXPECT_FALSE(fs::exists(temporary));
  EXPECT_FALSE(fs::exists(backup));
  EXPECT_EQ(text_of(restored), "old contents");
  fs::remove_all(dir);
}

TEST(Files, SigtermRemovesTemporariesAndRestoresBackups) { expect_signal_removes_temporary(SIGTERM); }
TEST(Files, SigintRemovesTemporariesAndRestoresBackups) { expect_signal_removes_temporary(SIGINT); }

TEST(Files, AReleasedGuardLeavesTheFile) {
  const fs::path dir = scratch("released");
  const fs::path file = dir / "kept.txt";
  put(file, "x");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    canalsim::InterruptGuard guard(file);
    guard.release();
    ::raise(SIGTERM);
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(fs::exists(file));
  fs::remove_all(dir);
}

}  // namespace
