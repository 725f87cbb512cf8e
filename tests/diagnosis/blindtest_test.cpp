// The blind benchmark's pieces: magnitudes in the issue's ranges, concealment, the error measure,
// and a tiny end-to-end run.
#include "diagnosis/blindtest.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "scenarios/builtin.hpp"

namespace canalsim::diagnosis {
namespace {

TEST(Blindtest, DrawsMagnitudesInTheIssueRanges) {
  std::mt19937_64 rng(1);
  for (int k = 0; k < 200; ++k) {
    const double rate = draw_effect("gate_rate_limit", rng).value;
    EXPECT_TRUE(rate >= 2.0 && rate <= 20.0);
    const double cd = draw_effect("discharge_coefficient", rng).value;
    EXPECT_TRUE((cd >= 0.8 && cd <= 0.92) || (cd >= 1.08 && cd <= 1.2)) << cd;
    const double n = draw_effect("friction", rng).value;
    EXPECT_TRUE(n == 0.5 || (n >= 2.0 && n <= 4.0)) << n;
    const double off = std::abs(draw_effect("sensor_offset", rng).value);
    EXPECT_TRUE(off >= 0.5 && off <= 3.0);
    const double lat = draw_effect("lateral_outflow", rng).value;
    EXPECT_TRUE(lat >= 0.03 && lat <= 0.15);
  }
}

TEST(Blindtest, SensorEffectsAreConcealedInTheSimulatorsOwnSensors) {
  scenarios::Scenario s = scenarios::builtin_scenario("lab");
  scenarios::ExperimentSpec e = *s.find_experiment("op1");
  conceal({"sensor_delay", 0.7}, s, e, 0.0);
  ASSERT_TRUE(e.sensors);
  EXPECT_DOUBLE_EQ(e.sensors->delay_s, 0.7);
  conceal({"gate_leakage", 2.0}, s, e, 0.0);
  EXPECT_NEAR(s.head_gate->leakage_m, 0.002, 1e-15);
}

TEST(Blindtest, ParameterErrorIsRelativeToTheDepartureFromNoEffect) {
  EXPECT_NEAR(parameter_error({"sensor_offset", 2.0}, 2.5), 0.25, 1e-12);
  // Cd 0.9 estimated 0.92: 0.02 of a 0.1 departure.
  EXPECT_NEAR(parameter_error({"discharge_coefficient", 0.9}, 0.92), 0.2, 1e-9);
  EXPECT_TRUE(std::isnan(parameter_error({"none", 0.0}, 1.0)));
}

TEST(Blindtest, ATinyRunScoresItsTrials) {
  BlindtestOptions o;
  o.trials = 2;
  o.seed = 5;
  o.experiments = {"op3"};
  o.duration_s = 40.0;
  o.effects = {"sensor_offset"};
  o.include_none = false;
  o.diagnose.candidates = {"sensor_offset"};
  o.diagnose.settle_time_s = 100.0;
  const BlindtestResult r = run_blindtest(scenarios::builtin_scenario("lab"), o);
  ASSERT_EQ(r.trials.size(), 2u);
  EXPECT_EQ(r.effect_trials, 2);
  EXPECT_EQ(r.confusion.size(), 1u);
  for (const auto& t : r.trials) EXPECT_EQ(t.truth.effect, "sensor_offset");
  EXPECT_NE(format_blindtest(r, o).find("top-1 accuracy"), std::string::npos);
  EXPECT_EQ(to_json(r)["trials"].size(), 2u);
}

// The realistic blind test end to end, small: a truth on twice the cells with the other limiter
// and perturbed physics, a clean baseline of another PRBS calibrated on, then one trial with a
// concealed sensor effect (a delay of 0.3–2 s or an offset of 0.5–3 mm) and one with two effects.
// What it proves: the calibrated diagnosis names the effect in recordings its model did not make,
// and the two-effect trial is scored on both names.
TEST(Blindtest, RealisticTrialsCalibrateOnABaselineOfAnotherTruthAndNameTheEffect) {
  BlindtestOptions o;
  o.trials = 1;
  o.seed = 3;
  o.experiments = {"op1", "op3"};
  o.duration_s = 60.0;
  o.effects = {"sensor_delay", "sensor_offset"};
  o.include_none = false;
  o.diagnose.candidates = {"sensor_delay", "sensor_offset", "discharge_coefficient"};
  o.diagnose.settle_time_s = 150.0;
  RealisticTruth realistic;
  realistic.numerics.cells_factor = 2;
  realistic.two_effect_trials = 1;
  o.realistic = realistic;
  const BlindtestResult r = run_blindtest(scenarios::builtin_scenario("lab"), o);
  ASSERT_EQ(r.trials.size(), 2u);
  const Trial& single = r.trials[0];
  EXPECT_TRUE(single.message.empty()) << single.message;
  EXPECT_NE(single.truth_drawn.find("cd_free"), std::string::npos);  // the truth was perturbed
  EXPECT_GT(single.calibration_seconds, 0.0);
  EXPECT_TRUE(single.correct) << single.truth.effect << " " << single.truth.value << " named " << single.verdict;
  const Trial& two = r.trials[1];
  ASSERT_TRUE(two.second);
  EXPECT_NE(two.truth.effect, two.second->effect);
  EXPECT_EQ(r.two_effect_trials, 1);
  EXPECT_EQ(r.effect_trials, 1);  // the two-effect trial is scored apart from the confusion matrix
  const nlohmann::json j = to_json(r);
  EXPECT_TRUE(j["trials"][1].contains("second"));
  EXPECT_NE(format_blindtest(r, o).find("two effects at once"), std::string::npos);
}

TEST(Blindtest, InvalidOptionsNameTheField) {
  BlindtestOptions o;
  o.trials = 0;
  EXPECT_NE(o.validate().message().find("trials"), std::string::npos);
  o = {};
  o.effects = {"gremlins"};
  EXPECT_NE(o.validate().message().find("gremlins"), std::string::npos);
  o = {};
  o.realistic = RealisticTruth{};
  o.realistic->noise_low_mm = 0.2;  // above noise_high_mm
  EXPECT_NE(o.validate().message().find("realistic.noise_low_mm"), std::string::npos) << o.validate().message();
  o.realistic->noise_low_mm = 0.03;
  o.model = ModelDiagnoseOptions{};
  EXPECT_NE(o.validate().message().find("realistic"), std::string::npos);
}

}  // namespace
}  // namespace canalsim::diagnosis
