// Argument checks shared by the subcommands. They run before any work, so that a mistyped flag
// value or an output path that cannot be written costs nothing and leaves nothing behind.
//
//   numbers : CLI11 validators. CLI11 prefixes their message with the option name, so a bad value
//             reads "--upstream-level: expected a level in mm > 0, got -5" — the flag the user
//             typed, not the library struct field it ends up in.
//   outputs : an output file's directory must exist (we do not create it: a typo in the path
//             should not silently make new directories); a directory flag that is documented to
//             be created needs every existing ancestor to be a writable directory.
#pragma once

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>
#include <unistd.h>

#include "core/files.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"

namespace canalsim::cli {

// ---- numeric flag values ----------------------------------------------------------------------

namespace detail {



// The whole string as a finite number, or nothing ("2x", "nan" and "" are not numbers).
inline bool parse_number(const std::string& text, double& value) {
  try {
    std::size_t used = 0;
    value = std::stod(text, &used);
    return used == text.size() && std::isfinite(value);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace detail

// A finite number in [low, high]; `what` says what the number is ("a level in mm").
inline CLI::Validator number_in(double low, double high, const std::string& what) {
  const std::string expected = "expected " + what + " in [" + format_g(low) + ", " +
                               format_g(high) + "]";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        if (!detail::parse_number(text, v) || v < low || v > high) return expected + ", got " + format_excerpt(text);
        return "";
      },
      "[" + format_g(low) + ", " + format_g(high) + "]");
}

// A finite number > 0 (no upper limit).
inline CLI::Validator positive_number(const std::string& what) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        if (!detail::parse_number(text, v) || !(v > 0.0)) return "expected " + what + " > 0, got " + format_excerpt(text);
        return "";
      },
      "> 0");
}

// An integer in [low, high]. Checked here rather than by CLI11's conversion, whose message
// ("Could not convert") names neither the range nor the kind of value expected.
inline CLI::Validator integer_in(long long low, long long high, const std::string& what) {
  const std::string expected =
      "expected " + what + " from " + std::to_string(low) + " to " + std::to_string(high);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        try {
          std::size_t used = 0;
          const long long v = std::stoll(text, &used);
          if (used == text.size() && v >= low && v <= high) return "";
        } catch (const std::exception&) {
        }
        return expected + ", got " + format_excerpt(text);
      },
      std::to_string(low) + ".." + std::to_string(high));
}

// A random seed: an integer from 0 to 2⁵³ (every one exact where a recording's metadata states it).
inline CLI::Validator seed_value() { return integer_in(0, 9007199254740992LL, "a seed"); }

// Worker threads: the same limits for every subcommand.
inline CLI::Validator thread_count() { return integer_in(1, 64, "a number of threads"); }

// ---- output paths -----------------------------------------------------------------------------

// FILE given to an output flag (--json FILE, -o FILE): its directory exists and FILE is new or a
// regular file (a device, FIFO or socket is never replaced; core/files.hpp). Writing happens
// after the work (atomically, via a temporary file next to FILE), so without this check a typo
// costs the whole run.
inline void check_output_file(const std::string& flag, const std::string& file) {
  namespace fs = std::filesystem;
  if (file.empty()) return;
  const fs::path path(file);
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(flag + " " + file + ": is a directory, expected a file name");
  if (const std::string problem = replaceable_file_problem(path); !problem.empty()) {
    throw InputError(flag + " " + file + ": " + problem);
  }
  if (!fs::exists(dir, ec)) throw InputError(flag + " " + file + ": directory " + dir.string() + " does not exist");
  if (!fs::is_directory(dir, ec)) throw InputError(flag + " " + file + ": " + dir.string() + " is not a directory");
  if (::access(dir.c_str(), W_OK) != 0) {
    throw InputError(flag + " " + file + ": directory " + dir.string() + " is not writable");
  }
}

// A file named on the command line: the flag that names it ("-o", "--json", "recording").
struct NamedFile {
  std::string flag;
  std::string path;
};

// True when `a` and `b` name one file: the same path, or two names of an existing file (links).
inline bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  const fs::path ca = fs::weakly_canonical(fs::absolute(a), ec), cb = fs::weakly_canonical(fs::absolute(b), ec);
  return ca == cb;
}

// Every output of a command, before any work: each as check_output_file wants it, no two naming
// the same file (one would be lost), and none naming an existing input (it would be overwritten;
// a built-in scenario's name is not a file).
inline void check_outputs(const std::vector<NamedFile>& outputs, const std::vector<NamedFile>& inputs = {}) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    if (outputs[i].path.empty()) continue;
    check_output_file(outputs[i].flag, outputs[i].path);
    for (std::size_t j = 0; j < i; ++j) {
      if (!outputs[j].path.empty() && same_file(outputs[i].path, outputs[j].path)) {
        throw InputError(outputs[i].flag + " " + outputs[i].path + ": the same file as " + outputs[j].flag + " " +
                         outputs[j].path + ": expected a different file for each output");
      }
    }
    for (const NamedFile& input : inputs) {
      std::error_code ec;
      if (std::filesystem::exists(input.path, ec) && same_file(outputs[i].path, input.path)) {
        throw InputError(outputs[i].flag + " " + outputs[i].path + ": the same file as the " + input.flag + " " +
                         input.path + ": expected an output that does not overwrite an input");
      }
    }
  }
}

// The inputs of a command given as a list of files (recordings), each named by `flag`.
inline std::vector<NamedFile> named_files(const std::string& flag, const std::vector<std::string>& paths) {
  std::vector<NamedFile> out;
  for (const auto& p : paths) out.push_back({flag, p});
  return out;
}

// DIR given to a flag that creates it when missing (simulate --out-dir): DIR is a directory, or
// the nearest existing ancestor is a writable directory, so that create_directory_for() will work.
inline void check_creatable_directory(const std::string& flag, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path existing = fs::path(dir);
  while (!existing.empty() && !fs::exists(existing, ec)) existing = existing.parent_path();
  if (existing.empty()) existing = ".";
  if (!fs::is_directory(existing, ec)) {
    throw InputError(flag + " " + dir + ": " + existing.string() + " exists and is not a directory");
  }
  if (::access(existing.c_str(), W_OK) != 0) {
    throw InputError(flag + " " + dir + ": directory " + existing.string() + " is not writable");
  }
}

// Creates DIR (and missing parents) for `flag`; one line naming the flag if the system refuses.
inline void create_directory_for(const std::string& flag, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(flag + " " + dir + ": cannot create the directory: " + ec.message());
}

}  // namespace canalsim::cli
