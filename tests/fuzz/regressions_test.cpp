// Replays fuzz/regressions/TARGET/* and fuzz/seeds/TARGET/* through the fuzz harness: an input that
// ever failed stays fixed. A breach of the harness's contract aborts this program (a failure).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "fuzz/harness.hpp"

namespace {

namespace fs = std::filesystem;

std::size_t replay(const std::string& target, const std::function<void(std::string_view)>& harness) {
  std::size_t inputs = 0;
  for (const char* kind : {"regressions", "seeds"}) {
    const fs::path dir = fs::path(CANALSIM_SOURCE_DIR) / "fuzz" / kind / target;
    if (!fs::is_directory(dir)) continue;
    for (const auto& entry : fs::directory_iterator(dir)) {
      std::ifstream in(entry.path(), std::ios::binary);
      std::stringstream bytes;
      bytes << in.rdbuf();
      SCOPED_TRACE(entry.path().string());
      harness(bytes.str());
      ++inputs;
    }
  }
  return inputs;
}

TEST(FuzzRegressions, ScenarioLoader) { EXPECT_GT(replay("scenario", canalsim::fuzz::scenario_input), 0u); }
TEST(FuzzRegressions, RecordingReader) { EXPECT_GT(replay("recording", canalsim::fuzz::recording_input), 0u); }
TEST(FuzzRegressions, Fitters) { EXPECT_GT(replay("fitting", canalsim::fuzz::fitting_input), 0u); }
TEST(FuzzRegressions, CommandLineArguments) {
  EXPECT_GT(replay("cli_arguments", canalsim::fuzz::cli_arguments_input), 0u);
}

}  // namespace
