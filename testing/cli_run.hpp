// Runs the canalsim program for the command-line tests: exit status, stderr and stdout, in a
// scratch directory of its own (relative paths in the arguments are relative to it).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace canalsim::cli_test {

namespace fs = std::filesystem;

struct RunResult {
  int status = 0;  // as returned by std::system
  int code = -1;   // the program's exit status (-1 if it did not exit normally)
  std::string err;
  std::string out;
};

inline std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline RunResult run_canalsim(const std::string& arguments, const fs::path& scratch) {
  const fs::path err = scratch / "stderr.txt", out = scratch / "stdout.txt";
  const std::string command = "cd '" + scratch.string() + "' && " + std::string(CANALSIM_PROGRAM) + " " + arguments +
                              " > " + out.string() + " 2> " + err.string();
  RunResult r;
  r.status = std::system(command.c_str());
  r.code = WIFEXITED(r.status) ? WEXITSTATUS(r.status) : -1;
  r.err = read_text(err);
  r.out = read_text(out);
  fs::remove(err);
  fs::remove(out);
  return r;
}

inline fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("canalsim_cli_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n' ? 1 : 0;
  return n;
}

// Everything in `dir` (files and directories, recursively): a failed run must not add to it.
inline std::size_t entry_count(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::recursive_directory_iterator(dir)) ++n;
  return n;
}

// The error contract of every subcommand: exit status 1 and exactly one line on stderr,
// "canalsim: error: ...".
inline bool is_one_error_line(const RunResult& r) {
  return r.code == 1 && count_lines(r.err) == 1 && r.err.rfind("canalsim: error: ", 0) == 0;
}

}  // namespace canalsim::cli_test
