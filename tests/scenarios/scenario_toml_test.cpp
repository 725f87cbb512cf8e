// Scenario TOML reader: a valid file gives the values written in it and the documented defaults;
// every kind of bad input gives one line naming file, line, key and the allowed range.
#include "scenarios/scenario_toml.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/recording.hpp"
#include "testing/refusals.hpp"

namespace canalsim::scenarios {
namespace {

const char* kMinimal = R"(
name = "flume"
[upstream]
kind = "level"
level_m = 0.06
[head_gate]
max_opening_m = 0.05
opening_m = 0.025
controlled = true
[[pools]]
length_m = 5.0
bottom_width_m = 0.08
cells = 100
[downstream]
kind = "gate"
[downstream.gate]
opening_m = 0.02
[[experiments]]
name = "op2"
operating_opening_mm = 25
)";

std::string error_of(const std::string& text) {
  return testing::input_error_of([&] { (void)parse_scenario(text, "s.toml"); }, "no error");
}

std::string with(const std::string& extra_after_pools) {
  std::string text = kMinimal;
  text.insert(text.find("[downstream]"), extra_after_pools);
  return text;
}

TEST(ScenarioToml, ReadsValuesAndAppliesDocumentedDefaults) {
  const Scenario s = parse_scenario(kMinimal, "s.toml");
  EXPECT_EQ(s.name, "flume");
  ASSERT_EQ(s.pools.size(), 1u);
  EXPECT_DOUBLE_EQ(s.pools[0].length_m, 5.0);
  EXPECT_DOUBLE_EQ(s.pools[0].side_slope, 0.0);
  EXPECT_DOUBLE_EQ(s.head_gate->opening_m, 0.025);
  EXPECT_TRUE(s.head_gate->controlled);
  EXPECT_DOUBLE_EQ(s.downstream.gate.opening_m, 0.02);
  EXPECT_DOUBLE_EQ(s.sensors.period_s, 0.13);
  EXPECT_DOUBLE_EQ(s.sensors.resolution_mm, 0.05);
  EXPECT_DOUBLE_EQ(s.numerics.cfl, 0.8);
  ASSERT_NE(s.find_experiment("op2"), nullptr);
  EXPECT_EQ(s.find_experiment("op2")->input.prbs_stages, 9);
  EXPECT_DOUBLE_EQ(s.find_experiment("op2")->input.prbs_clock_s, 0.5);
}

TEST(ScenarioToml, NegativeWidthNamesFileLineKeyAndRange) {
  std::string text = kMinimal;
  text.replace(text.find("bottom_width_m = 0.08"), 21, "bottom_width_m = -0.08");
  EXPECT_EQ(error_of(text), "s.toml:12: pools[0].bottom_width_m = -0.08: expected a number in [0.001, 1000] m");
}

TEST(ScenarioToml, CflAboveOneIsRejected) {
  EXPECT_EQ(error_of(with("[numerics]\ncfl = 1.5\n")),
            "s.toml:15: numerics.cfl = 1.5: expected a number in (0, 1]");
}

TEST(ScenarioToml, NonPositiveSamplingPeriodIsRejected) {
  EXPECT_EQ(error_of(with("[sensors]\nperiod_s = 0\n")),
            "s.toml:15: sensors.period_s = 0: expected a number in (0, 3600] s");
}

TEST(ScenarioToml, UnknownKeyIsNamed) {
  EXPECT_EQ(error_of(with("[numerics]\ncfll = 0.5\n")),
            "s.toml:15: unknown key numerics.cfll (docs/scenarios.md lists the keys)");
}

TEST(ScenarioToml, GateOpeningAboveItsMaximumIsRejected) {
  std::string text = kMinimal;
  text.replace(text.find("opening_m = 0.025"), 17, "opening_m = 0.06");
  EXPECT_EQ(error_of(text), "s.toml:8: head_gate.opening_m = 0.06: expected a number in [0, 0.05] m");
}

TEST(ScenarioToml, GateAboveTheWallIsRejected) {
  std::string text = kMinimal;
  text.replace(text.find("max_opening_m = 0.05"), 20, "max_opening_m = 0.3");
  // A check across two keys still names the line of the key it blames, and the values as written.
  EXPECT_EQ(error_of(text),
            "s.toml:7: head_gate.max_opening_m = 0.3 m: expected at most the wall height of pool 'pool' (0.25 m)");
}

TEST(ScenarioToml, OperatingPointOutsideTheGateRangeIsRejected) {
  std::string text = kMinimal;
  text.replace(text.find("operating_opening_mm = 25"), 25, "operating_opening_mm = 80");
  EXPECT_EQ(error_of(text),
            "s.toml:20: experiments[0].operating_opening_mm = 80 mm: expected at most the gate's max_opening_m (50 mm)");
}

TEST(ScenarioToml, WrongTypeAndBadChoiceAreNamed) {
  EXPECT_EQ(error_of(with("[numerics]\norder = \"two\"\n")),
            "s.toml:15: numerics.order is a string: expected an integer in [1, 2]");
  std::string text = kMinimal;
  text.replace(text.find("kind = \"level\""), 14, "kind = \"lake\"");
  EXPECT_EQ(error_of(text),
            "s.toml:4: upstream.kind = \"lake\": expected one of level, reservoir, discharge, recorded");
}

TEST(ScenarioToml, SyntaxErrorGivesFileAndLine) {
  EXPECT_EQ(error_of("name = \n").rfind("s.toml:1: not valid TOML (", 0), 0u);
}

TEST(ScenarioToml, EmptyFileAsksForPools) {
  EXPECT_EQ(error_of(""), "s.toml:1: pools: missing: expected at least one [[pools]] table (see docs/scenarios.md)");
}

TEST(ScenarioToml, UnboundedRangeIsWrittenOpen) {
  EXPECT_EQ(error_of(std::string(kMinimal) + "[experiments.input]\nkind = \"step\"\nstart_s = -1\n"),
            "s.toml:23: experiments[0].input.start_s = -1: expected a number in [0, ∞) s");
}

// An input series is read when the scenario is, from the scenario file's folder.
TEST(ScenarioToml, InputFileIsReadBesideTheScenarioAtLoad) {
  const auto dir = std::filesystem::temp_directory_path() / ("canalsim_input_file_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "data");
  const std::string scenario = std::string(kMinimal) + "[experiments.input]\nkind = \"file\"\nfile = \"data/u.csv\"\n";
  { std::ofstream(dir / "s.toml") << scenario; }
  try {
    load_scenario(dir / "s.toml");
    ADD_FAILURE() << "a missing series must stop the load";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind((dir / "s.toml").string() + ":23: experiments[0].input.file = \"data/u.csv\": " +
                                              (dir / "data/u.csv").string() + ": cannot open the recording",
                                          0),
              0u)
        << e.what();
  }
  { std::ofstream(dir / "data/u.csv") << "t_s,u_mm\n0,25\n0.13,30\n"; }
  const Scenario s = load_scenario(dir / "s.toml");  // from another working directory
  EXPECT_EQ(s.experiments[0].input.file, (dir / "data/u.csv").string());
  std::filesystem::remove_all(dir);
}

TEST(ScenarioToml, GateCountMustMatchPools) {
  EXPECT_NE(error_of(with("[[pools]]\nlength_m = 3\nbottom_width_m = 0.08\n")).find("gates"),
            std::string::npos);
}

TEST(ScenarioToml, UnreadableFileIsNamed) {
  EXPECT_THROW(load_scenario("/nonexistent/s.toml"), InputError);
}

}  // namespace
}  // namespace canalsim::scenarios
