#include "fuzz/harness.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/command_line.hpp"
#include "core/errors.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario_toml.hpp"

namespace canalsim::fuzz {
namespace {

[[noreturn]] void breach(const std::string& what) {
  std::fprintf(stderr, "fuzz contract breached: %s\n", what.c_str());
  std::abort();
}

// Restores std::cout and std::cerr on every exit path.
class CapturedStreams {
 public:
  CapturedStreams() : out_(std::cout.rdbuf(discarded_.rdbuf())), err_(std::cerr.rdbuf(captured_.rdbuf())) {}
  ~CapturedStreams() {
    std::cout.rdbuf(out_);
    std::cerr.rdbuf(err_);
  }
  std::string err() const { return captured_.str(); }

 private:
  std::ostringstream discarded_, captured_;
  std::streambuf* out_;
  std::streambuf* err_;
};

}  // namespace

void scenario_input(std::string_view bytes) {
  try {
    (void)scenarios::parse_scenario(std::string(bytes), "fuzz.toml");
  } catch (const InputError&) {
  }
}

void recording_input(std::string_view bytes) {
  Recording first;
  try {
    first = parse_recording(std::string(bytes), "fuzz.csv");
  } catch (const InputError&) {
    return;
  }
  Recording again;
  try {
    again = parse_recording(format_recording(first), "rewritten.csv");
  } catch (const InputError& e) {
    // Ten significant digits can merge time stamps that differed further down (t = 1e6 s with a
    // 1e-5 s step): the rewritten axis is then refused, which is the reader doing its job.
    if (std::string(e.what()).find("t_s") == std::string::npos) breach(std::string("rewritten recording refused: ") + e.what());
    return;
  }
  if (again.metadata.size() != first.metadata.size()) breach("metadata lines changed in the round trip");
  if (again.names != first.names) breach("columns changed in the round trip");
  if (again.size() != first.size()) breach("rows changed in the round trip");
}

void cli_arguments_input(std::string_view bytes) {
  std::vector<std::string> arguments{"canalsim"};
  std::string current;
  for (char c : bytes.substr(0, 4096)) {
    if (c == '\0') {
      arguments.push_back(current);
      current.clear();
      if (arguments.size() > 24) break;
    } else {
      current.push_back(c);
    }
  }
  if (!current.empty() && arguments.size() <= 24) arguments.push_back(current);
  std::vector<char*> argv;
  for (auto& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);

  // Parsing, validation and requirements done, the application's parse-complete callback runs
  // before any subcommand's: it stops there. (Replacing the subcommands' callbacks instead would
  // free the argument structs their options write into: the first version of this harness did,
  // fuzz/regressions/cli_arguments/crash-26324df0...)
  struct ParsedOnly {};
  CLI::App app{"canalsim"};
  cli::add_all_commands(app);
  app.parse_complete_callback([] { throw ParsedOnly{}; });
  int code = 0;
  std::string err;
  {
    CapturedStreams streams;
    try {
      code = cli::run_command_line(app, static_cast<int>(arguments.size()), argv.data());
    } catch (const ParsedOnly&) {
      code = 0;
    }
    err = streams.err();
  }
  if (code != 0 && code != 1) breach("exit status " + std::to_string(code));
  if (code == 1) {
    const auto lines = std::count(err.begin(), err.end(), '\n');
    if (lines != 1 || err.rfind("canalsim: error: ", 0) != 0) breach("error output is not one line: " + err.substr(0, 300));
  }
}

}  // namespace canalsim::fuzz
