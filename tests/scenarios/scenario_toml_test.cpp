// Scenario TOML reader: a valid file gives the values written in it and the documented defaults;
// every kind of bad input gives one line naming file, line, key and the allowed range.
#include "scenarios/scenario_toml.hpp"

#include <gtest/gtest.h>

#include "scenarios/recording.hpp"

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
  try {
    parse_scenario(text, "s.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
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
  EXPECT_EQ(error_of(text), "s.toml:12: pools[0].bottom_width_m = -0.08: expected a number in (0, 1000] m");
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
  EXPECT_NE(error_of(text).find("head_gate.max_opening_m"), std::string::npos);
  EXPECT_NE(error_of(text).find("wall height"), std::string::npos);
}

TEST(ScenarioToml, OperatingPointOutsideTheGateRangeIsRejected) {
  std::string text = kMinimal;
  text.replace(text.find("operating_opening_mm = 25"), 25, "operating_opening_mm = 80");
  EXPECT_NE(error_of(text).find("experiments[0].operating_opening_mm"), std::string::npos);
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
  EXPECT_EQ(error_of("name = \n").rfind("s.toml:1: ", 0), 0u);
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
