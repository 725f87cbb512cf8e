// Runs the canalsim program for the command-line tests: exit status and stderr, in a scratch
// directory of its own.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace canalsim::cli_test {

namespace fs = std::filesystem;

struct RunResult {
  int status = 0;
  std::string err;
};

inline RunResult run_canalsim(const std::string& arguments, const fs::path& scratch) {
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

}  // namespace canalsim::cli_test
