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
#include <unistd.h>

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

// Worker threads: the same limits for every subcommand.
inline CLI::Validator thread_count() { return integer_in(1, 64, "a number of threads"); }

// ---- output paths -----------------------------------------------------------------------------

// FILE given to an output flag (--json FILE, -o FILE): its directory exists and FILE is not a
// directory. Writing happens after the work (atomically, via a temporary file next to FILE), so
// without this check a typo costs the whole run.
inline void check_output_file(const std::string& flag, const std::string& file) {
  namespace fs = std::filesystem;
  if (file.empty()) return;
  const fs::path path(file);
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(flag + " " + file + ": is a directory, expected a file name");
  if (!fs::exists(dir, ec)) throw InputError(flag + " " + file + ": directory " + dir.string() + " does not exist");
  if (!fs::is_directory(dir, ec)) throw InputError(flag + " " + file + ": " + dir.string() + " is not a directory");
  if (::access(dir.c_str(), W_OK) != 0) {
    throw InputError(flag + " " + file + ": directory " + dir.string() + " is not writable");
  }
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
