// The error contract in the command-line tests: a command that must fail ends with exit status 1
// and one line "canalsim: error: ..." on stderr (testing/cli_run.hpp is_one_error_line), and that
// line names what the test expects (the flag, file, key or value, and what was expected).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "testing/cli_run.hpp"

namespace canalsim::cli_test {

// Whether `r` is one error line that contains `expected`; a failure shows the exit status and
// what the program wrote.
inline ::testing::AssertionResult fails_naming(const RunResult& r, const std::string& expected) {
  if (!is_one_error_line(r)) {
    return ::testing::AssertionFailure() << "not one error line (exit status " << r.code << "): " << r.err << r.out;
  }
  if (r.err.find(expected) == std::string::npos) {
    return ::testing::AssertionFailure() << "the error does not say '" << expected << "': " << r.err;
  }
  return ::testing::AssertionSuccess();
}

// A command and what its one error line must say.
struct ErrorCase {
  std::string command, expected;
};

// Runs each command in `scratch`: each must fail naming what it expects, and say none of
// `never_said` (what a user cannot act on: CLI11's hints, the library's field names).
inline void expect_errors(const std::vector<ErrorCase>& cases, const fs::path& scratch,
                          const std::vector<std::string>& never_said = {}) {
  for (const ErrorCase& c : cases) {
    const RunResult r = run_canalsim(c.command, scratch);
    EXPECT_TRUE(fails_naming(r, c.expected)) << c.command;
    for (const std::string& text : never_said) EXPECT_EQ(r.err.find(text), std::string::npos) << r.err;
  }
}

// `command`, run in `scratch`, fails naming `expected` and leaves none of `unwritten` (paths
// relative to scratch): a refused command writes nothing.
inline void expect_refused_writing_nothing(const fs::path& scratch, const std::string& command,
                                           const std::string& expected, const std::vector<std::string>& unwritten) {
  EXPECT_TRUE(fails_naming(run_canalsim(command, scratch), expected)) << command;
  for (const std::string& path : unwritten) EXPECT_FALSE(fs::exists(scratch / path)) << path;
}

}  // namespace canalsim::cli_test
