#include "fuzz/harness.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli/command_line.hpp"
#include "core/errors.hpp"
#include "core/recording.hpp"
#include "core/resample.hpp"
#include "scenarios/scenario_toml.hpp"

namespace canalsim::fuzz {
namespace {

[[noreturn]] void breach(const std::string& what) {
  std::fprintf(stderr, "fuzz contract breached: %s\n", what.c_str());
  std::abort();
}

// Captures std::cout and std::cerr, and restores them on every exit path.
class CapturedStreams {
 public:
  CapturedStreams() : out_(std::cout.rdbuf(captured_out_.rdbuf())), err_(std::cerr.rdbuf(captured_err_.rdbuf())) {}
  ~CapturedStreams() {
    std::cout.rdbuf(out_);
    std::cerr.rdbuf(err_);
  }
  std::string out() const { return captured_out_.str(); }
  std::string err() const { return captured_err_.str(); }

 private:
  std::ostringstream captured_out_, captured_err_;
  std::streambuf* out_;
  std::streambuf* err_;
};

// Runs `arguments` (without the program name) as `canalsim` would: the exit status, stdout, stderr.
struct Run {
  int code = 0;
  std::string out, err;
};

Run run_canalsim(const std::vector<std::string>& given) {
  std::vector<std::string> arguments{"canalsim"};
  arguments.insert(arguments.end(), given.begin(), given.end());
  std::vector<char*> argv;
  for (auto& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);
  CLI::App app{"canalsim"};
  cli::add_all_commands(app);
  Run run;
  bool escaped = false;
  {
    CapturedStreams streams;
    try {
      run.code = cli::run_command_line(app, static_cast<int>(arguments.size()), argv.data());
    } catch (...) {
      escaped = true;
    }
    run.out = streams.out();
    run.err = streams.err();
  }
  if (escaped) breach("an exception escaped the command line");
  return run;
}

// True when `text` holds the word nan or inf in any case ("-nan", "inf%", not "information").
bool prints_non_finite(const std::string& text) {
  std::string lower(text);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const auto letter = [&](std::size_t i) { return i < lower.size() && std::isalpha(static_cast<unsigned char>(lower[i])); };
  for (const std::string word : {"nan", "inf"}) {
    for (std::size_t at = lower.find(word); at != std::string::npos; at = lower.find(word, at + 1)) {
      if ((at == 0 || !letter(at - 1)) && !letter(at + word.size())) return true;
    }
  }
  return false;
}

// The command's contract: status 0 or 1, one error line on failure, finite numbers on success.
void check_contract(const Run& run, const std::string& command) {
  if (run.code != 0 && run.code != 1) breach(command + ": exit status " + std::to_string(run.code));
  if (run.code == 1) {
    // Progress and warning lines may come first; the error is the one line that starts with the
    // prefix (the text it quotes may hold the prefix too), and it is the last.
    std::vector<std::string> lines;
    std::istringstream in(run.err);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    const auto errors = std::count_if(lines.begin(), lines.end(),
                                      [](const std::string& l) { return l.rfind("canalsim: error: ", 0) == 0; });
    if (errors != 1 || lines.empty() || lines.back().rfind("canalsim: error: ", 0) != 0 || run.err.back() != '\n') {
      breach(command + ": the error is not one line: " + run.err.substr(0, 300));
    }
    return;
  }
  if (prints_non_finite(run.out)) breach(command + ": a non-finite number printed with status 0: " + run.out.substr(0, 600));
}

constexpr const char* kModels[] = {"liom", "sopd", "lfom", "nliom-f", "nlfom-f", "nliom-s", "nlfom-s", "hybrid", "id", "idz"};
constexpr std::size_t kModelCount = std::size(kModels);
constexpr const char* kPeriods[] = {"0.01", "0.13", "0.5", "3", "1e-6"};

}  // namespace

void fitting_input(std::string_view bytes) {
  if (bytes.size() < 2) return;
  const auto action = static_cast<unsigned char>(bytes[0]) % (kModelCount + 2);
  const auto choice = static_cast<unsigned char>(bytes[1]);
  const std::string text(bytes.substr(2));
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("canalsim_fitting_fuzz_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string recording = (dir / "recording.csv").string(), output = (dir / "out.csv").string();
  std::ofstream(recording, std::ios::binary | std::ios::trunc) << text;

  std::vector<std::string> arguments;
  if (action < kModelCount) {
    arguments = {"fit", "-m", kModels[action], "--threads", "1", recording};
  } else if (action == kModelCount) {
    arguments = {"diagnose", "--model", kModels[choice % kModelCount], "--threads", "1", recording};
  } else {
    // Resampling is bounded by ceilings (core/resample.hpp) that allow minutes of work; only the
    // inputs that stay well below them run here, so that a slow but legitimate resampling is not
    // taken for a hang. The refusals past the ceilings run in any case.
    const std::string period = kPeriods[choice % std::size(kPeriods)];
    try {
      const Recording in = parse_recording(text, recording, [] {
        RecordingReadOptions o;
        o.required = {columns::time};
        o.uniform_tolerance = std::numeric_limits<double>::infinity();
        return o;
      }());
      ResampleOptions o;
      o.period_s = std::stod(period);
      const ResampleCost cost = estimate_resample_cost(in, o);
      const bool past_ceiling = cost.rows > kMaxResampledRows || cost.fine_samples > kMaxFineSamples ||
                                cost.filter_operations > kMaxFilterOperations;
      if (!past_ceiling && (cost.rows > 2e5 || cost.filter_operations > 2e7)) return;
    } catch (const InputError&) {
    }
    arguments = {"resample", recording, "-o", output, "--period", period};
  }
  std::string command;
  for (const auto& a : arguments) command += (command.empty() ? "" : " ") + a;
  check_contract(run_canalsim(arguments), command);
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

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
  // free the argument structs their options write into; fuzz/regressions/cli_arguments/
  // crash-26324df0... is the input that shows it.)
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
