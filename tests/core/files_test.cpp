// Writing files all or nothing: a set of files either all replace what was there or none does,
// and nothing is left behind — after a failure, and after SIGINT/SIGTERM in the middle.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/stat.h>
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
// A closed terminal ends a run like Ctrl-C does.
TEST(Files, SighupRemovesTemporariesAndRestoresBackups) { expect_signal_removes_temporary(SIGHUP); }

// Only regular files are replaced: a device, a FIFO, or a link to one is refused before anything
// is written (as root, renaming over /dev/full would replace the system's device with a file).
TEST(Files, ADeviceAFifoOrALinkToOneIsNeverReplaced) {
  const fs::path dir = scratch("not_regular");
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_symlink("/dev/null", dir / "to_null");
  put(dir / "a.txt", "old a");
  for (const fs::path& target : {fs::path("/dev/null"), dir / "fifo", dir / "to_null"}) {
    try {
      canalsim::write_files_atomically({{dir / "a.txt", "new a"}, {target, "x"}});
      ADD_FAILURE() << target << " was replaced";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("expected a regular file (or a new path) to write"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_EQ(text_of(dir / "a.txt"), "old a");
  EXPECT_EQ(entries(dir), 3u);  // fifo, to_null, a.txt: no temporary, no backup
  fs::remove_all(dir);
}

// A symbolic link is written through: its target gets the contents, the link stays a link, and
// the replaced file keeps its permissions. A dangling link into a missing directory fails the
// whole set, which then touches nothing.
TEST(Files, ALinkIsWrittenThroughAndTheFileKeepsItsMode) {
  const fs::path dir = scratch("link");
  put(dir / "target.json", "old");
  fs::permissions(dir / "target.json", fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  fs::create_symlink("target.json", dir / "out.json");
  canalsim::write_files_atomically({{dir / "out.json", "new"}});
  EXPECT_TRUE(fs::is_symlink(dir / "out.json"));
  EXPECT_EQ(text_of(dir / "target.json"), "new");
  EXPECT_EQ(fs::status(dir / "target.json").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  fs::create_symlink("missing/r.html", dir / "dangling.html");
  put(dir / "a.txt", "old a");
  EXPECT_THROW(canalsim::write_files_atomically({{dir / "a.txt", "new a"}, {dir / "dangling.html", "r"}}), InputError);
  EXPECT_EQ(text_of(dir / "a.txt"), "old a");
  EXPECT_TRUE(fs::is_symlink(dir / "dangling.html"));
  EXPECT_EQ(entries(dir), 4u);  // target.json, out.json, dangling.html, a.txt
  fs::remove_all(dir);
}

// A file that cannot be renamed over (immutable: even root cannot replace it) fails the set after
// the earlier files were renamed into place: they get their contents back, and no backup is left
// of the file that was never replaced.
TEST(Files, AFileThatCannotBeReplacedLeavesNoBackup) {
  const fs::path dir = scratch("immutable");
  put(dir / "a.txt", "old a");
  put(dir / "b.txt", "old b");
  if (std::system(("chattr +i '" + (dir / "b.txt").string() + "' 2>/dev/null").c_str()) != 0) {
    fs::remove_all(dir);
    GTEST_SKIP() << "the file system has no immutable flag here";
  }
  EXPECT_THROW(canalsim::write_files_atomically({{dir / "a.txt", "new a"}, {dir / "b.txt", "new b"}}), InputError);
  EXPECT_EQ(std::system(("chattr -i '" + (dir / "b.txt").string() + "'").c_str()), 0);
  EXPECT_EQ(text_of(dir / "a.txt"), "old a");
  EXPECT_EQ(text_of(dir / "b.txt"), "old b");
  EXPECT_EQ(entries(dir), 2u);  // no *.tmp.*, no *.bak.*
  fs::remove_all(dir);
}

// Two names of one file in a set would lose one output: refused before anything is written.
TEST(Files, TwoNamesOfOneFileAreRefused) {
  const fs::path dir = scratch("twice");
  fs::create_symlink("a.txt", dir / "b.txt");
  EXPECT_THROW(canalsim::write_files_atomically({{dir / "a.txt", "1"}, {dir / "b.txt", "2"}}), InputError);
  EXPECT_THROW(canalsim::write_files_atomically({{dir / "a.txt", "1"}, {dir / "." / "a.txt", "2"}}), InputError);
  EXPECT_EQ(entries(dir), 1u);
  fs::remove_all(dir);
}

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
