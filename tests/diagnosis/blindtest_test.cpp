// The blind benchmark's pieces: magnitudes from the catalog's draws, the logger that makes
// instrument faults, the error measure, and a tiny end-to-end run.
#include "diagnosis/blindtest.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "scenarios/builtin.hpp"
#include "testing/refusals.hpp"

namespace canalsim::diagnosis {
namespace {

TEST(Blindtest, DrawsMagnitudesInTheCatalogRanges) {
  std::mt19937_64 rng(1);
  for (int k = 0; k < 200; ++k) {
    const double rate = draw_effect("gate_rate_limit", rng).value;
    EXPECT_TRUE(rate >= 2.0 && rate <= 20.0);
    const double cd = draw_effect("discharge_coefficient", rng).value;
    EXPECT_TRUE((cd >= 0.8 && cd <= 0.92) || (cd >= 1.08 && cd <= 1.2)) << cd;
    const double n = draw_effect("friction", rng).value;
    EXPECT_TRUE((n >= 0.25 && n <= 0.5) || (n >= 2.0 && n <= 4.0)) << n;
    const ConcealedEffect off = draw_effect("sensor_offset", rng, {"y_up_mm", "y_dwe_mm"});
    EXPECT_TRUE(std::abs(off.value) >= 0.5 && std::abs(off.value) <= 3.0);
    EXPECT_TRUE(off.effect == "sensor_offset[y_up_mm]" || off.effect == "sensor_offset[y_dwe_mm]") << off.effect;
    const double lat = draw_effect("lateral_outflow", rng).value;
    EXPECT_TRUE(lat >= 0.03 && lat <= 0.15);
  }
}

// The logger writes each fault in its closed form on the faulty channel alone: a smooth ideal
// recording (a sine, on which a cubic delay is exact to ~1e-4 mm) with no noise or lattice.
TEST(Blindtest, TheLoggerFaultsOneChannelInItsClosedForm) {
  const double h = 0.1, w = 2.0 * 3.141592653589793 / 20.0;
  Recording ideal;
  std::vector<double> t, u, x, up, dw, dwe;
  for (int k = 0; k < 600; ++k) {
    t.push_back(h * k);
    u.push_back(k < 300 ? 20.0 : 25.0);
    x.push_back(20.0 + std::sin(w * h * k));
    up.push_back(60.0 + std::sin(w * h * k));
    dw.push_back(48.0 + std::cos(w * h * k));
    dwe.push_back(44.0 + std::sin(w * h * k));
  }
  for (const auto& [name, v] : {std::pair{"t_s", t}, {"u_mm", u}, {"x_up_mm", x}, {"y_up_mm", up}, {"y_dw_mm", dw},
                                {"y_dwe_mm", dwe}}) {
    ideal.set_column(name, v);
  }
  const Recording r = as_logged(ideal,
                                {{"sensor_delay[y_dwe_mm]", 0.75}, {"sensor_drift[y_up_mm]", 0.6},
                                 {"sensor_scale[y_dw_mm]", 1.05}, {"command_offset", 2.0}},
                                {0.0, 0.0, 1});
  for (int k = 20; k < 600; ++k) {
    const double tk = h * k;
    EXPECT_NEAR(r.column("y_dwe_mm")[k], 44.0 + std::sin(w * (tk - 0.75)), 2e-4) << k;
    EXPECT_NEAR(r.column("y_up_mm")[k], up[k] + 0.6 * tk / 60.0, 1e-12) << k;
    EXPECT_NEAR(r.column("y_dw_mm")[k], 1.05 * dw[k], 1e-12) << k;
    EXPECT_NEAR(r.column("u_mm")[k], u[k] + 2.0, 1e-12) << k;  // logged 2 mm above the gate
    EXPECT_DOUBLE_EQ(r.column("x_up_mm")[k], x[k]);
  }
  // A clock between the command and every reading shifts the gate position too; a coarse lattice
  // of one sensor sits at an offset of its own.
  const Recording late = as_logged(ideal, {{"command_delay", 0.5}, {"sensor_quantization[y_up_mm]", 0.4}}, {0.0, 0.05, 3});
  EXPECT_NEAR(late.column("x_up_mm")[100], 20.0 + std::sin(w * (10.0 - 0.5)), 2e-4);
  const double lattice = std::fmod(late.column("y_up_mm")[0], 0.4);
  for (double v : late.column("y_up_mm")) EXPECT_NEAR(std::remainder(v - lattice, 0.4), 0.0, 1e-9);
  for (double v : late.column("y_dwe_mm")) EXPECT_NEAR(std::remainder(v, 0.05), 0.0, 1e-9);
  // The lattice is the instrument's: another recording it writes (another logger seed, another
  // experiment) sits on the same one.
  Recording other_experiment = ideal;
  std::vector<double> higher = up;
  for (double& v : higher) v += 0.137;
  other_experiment.set_column("y_up_mm", higher);
  const Recording later = as_logged(other_experiment, {{"sensor_quantization[y_up_mm]", 0.4}}, {0.0, 0.05, 4});
  for (double v : later.column("y_up_mm")) EXPECT_NEAR(std::remainder(v - lattice, 0.4), 0.0, 1e-9);
}

TEST(Blindtest, OnlyHydraulicEffectsAreConcealedInTheScenario) {
  scenarios::Scenario s = scenarios::builtin_scenario("lab");
  const scenarios::Scenario lab = s;
  conceal({"sensor_delay[y_dwe_mm]", 0.7}, s, 0.0);
  conceal({"command_offset", 1.0}, s, 0.0);
  EXPECT_EQ(s.head_gate->leakage_m, lab.head_gate->leakage_m);
  conceal({"gate_leakage", 2.0}, s, 0.0);
  EXPECT_NEAR(s.head_gate->leakage_m, 0.002, 1e-15);
}

// The realistic test's second simulator (`--truth-scheme staggered`) carries every way an
// effect is concealed: the scenario edited (an outflow along the pool), the drive (a gate behind
// a backlash) and the logger (an offset of one sensor).
TEST(Blindtest, ConcealedEffectsReachTheSecondSimulator) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  scenarios::ExperimentSpec e = *lab.find_experiment("op2");
  e.duration_s = 40.0;
  const scenarios::Simulator staggered = scenarios::staggered_simulator();
  const double inflow_m3s = 1.0e-3;
  const auto run = [&](const std::vector<ConcealedEffect>& concealed) {
    return simulate_concealed(lab, e, concealed, inflow_m3s, {}, staggered);
  };
  const auto mean = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  const Recording clean = run({});
  EXPECT_NE(clean.meta("generator").find("staggered"), std::string::npos);
  const Recording outflow = run({{"lateral_outflow", 0.2}});  // 0.2 L/s drawn at mid-pool
  EXPECT_LT(mean(outflow.column("y_dwe_mm")), mean(clean.column("y_dwe_mm")) - 1.0);
  const Recording backlash = run({{"gate_backlash", 3.0}});
  EXPECT_EQ(backlash.column("u_mm"), clean.column("u_mm"));  // the logger records the command ...
  EXPECT_NE(backlash.column("x_up_mm"), clean.column("x_up_mm"));  // ... not what the gate did
  const Recording offset = run({{"sensor_offset[y_dwe_mm]", 1.5}});
  EXPECT_NEAR(mean(offset.column("y_dwe_mm")) - mean(clean.column("y_dwe_mm")), 1.5, 0.03);
  EXPECT_EQ(offset.column("y_dw_mm"), clean.column("y_dw_mm"));
}

TEST(Blindtest, ATwinCountsOnlyWithoutAGatePosition) {
  EXPECT_TRUE(names_effect("gate_leakage", "command_offset", false));
  EXPECT_FALSE(names_effect("gate_leakage", "command_offset", true));
  EXPECT_TRUE(names_effect("sensor_offset[y_up_mm]", "sensor_offset[y_up_mm]", true));
  EXPECT_FALSE(names_effect("sensor_offset[y_dwe_mm]", "sensor_offset[y_up_mm]", false));
}

TEST(Blindtest, ParameterErrorIsRelativeToTheDepartureFromNoEffect) {
  EXPECT_NEAR(parameter_error({"sensor_offset[y_dwe_mm]", 2.0}, 2.5), 0.25, 1e-12);
  EXPECT_NEAR(parameter_error({"gate_rate_limit", 10.0}, 12.0), 0.2, 1e-12);
  // Cd 0.9 estimated 0.92: 0.02 of a 0.1 departure.
  EXPECT_NEAR(parameter_error({"discharge_coefficient", 0.9}, 0.92), 0.2, 1e-9);
  EXPECT_TRUE(std::isnan(parameter_error({"none", 0.0}, 1.0)));
}

// A blind test small enough for a unit test: `trials` of 40 s of op3, drawing and diagnosing
// among `effects`.
BlindtestOptions tiny(int trials, std::uint64_t seed, const std::vector<std::string>& effects) {
  BlindtestOptions o;
  o.trials = trials;
  o.seed = seed;
  o.experiments = {"op3"};
  o.duration_s = 40.0;
  o.effects = effects;
  o.diagnose.candidates = effects;
  o.diagnose.settle_time_s = 100.0;
  return o;
}

TEST(Blindtest, ATinyRunScoresItsTrials) {
  BlindtestOptions o = tiny(2, 5, {"sensor_offset"});
  o.include_none = false;
  const BlindtestResult r = run_blindtest(scenarios::builtin_scenario("lab"), o);
  ASSERT_EQ(r.trials.size(), 2u);
  EXPECT_EQ(r.effect_trials, 2);
  EXPECT_EQ(r.confusion.size(), 1u);
  for (const auto& t : r.trials) EXPECT_EQ(t.truth.effect.rfind("sensor_offset[", 0), 0u) << t.truth.effect;
  EXPECT_EQ(r.channel_trials, 2);
  EXPECT_NE(format_blindtest(r, o).find("top-1 accuracy"), std::string::npos);
  EXPECT_EQ(to_json(r)["trials"].size(), 2u);
}

// A trial's outcome depends on its index alone, so a trial re-run by `only` is the trial of the
// full test: the same concealed effect, verdict and estimate.
TEST(Blindtest, ATrialReRunAloneIsTheTrialOfTheFullRun) {
  BlindtestOptions o = tiny(3, 9, {"sensor_offset", "sensor_delay"});
  const BlindtestResult full = run_blindtest(scenarios::builtin_scenario("lab"), o);
  o.only = {2};
  const BlindtestResult alone = run_blindtest(scenarios::builtin_scenario("lab"), o);
  ASSERT_EQ(alone.trials.size(), 1u);
  const Trial& a = alone.trials.front();
  const Trial& f = full.trials.at(2);
  EXPECT_EQ(a.index, 2);
  EXPECT_EQ(a.truth.effect, f.truth.effect);
  EXPECT_EQ(a.truth.value, f.truth.value);
  EXPECT_EQ(a.verdict, f.verdict);
  EXPECT_EQ(a.estimate, f.estimate);
  o.only = {3};
  EXPECT_THROW(run_blindtest(scenarios::builtin_scenario("lab"), o), InputError);
}

// The realistic blind test end to end, small: a truth on twice the cells with the other limiter
// and perturbed physics, a clean baseline of another PRBS calibrated on, then one trial with a
// concealed fault of one level sensor (a delay of 0.3–2 s or an offset of 0.5–3 mm, either sign)
// and one with two effects. What it proves: the calibrated diagnosis names the effect and its
// channel in recordings its model did not make, and the two-effect trial is scored on both names.
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
  EXPECT_TRUE(single.channel_right);
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
  using testing::refuses;
  const auto no_trials = [](BlindtestOptions& o) { o.trials = 0; };
  const auto unknown_effect = [](BlindtestOptions& o) { o.effects = {"gremlins"}; };
  const auto noise_range_reversed = [](BlindtestOptions& o) {
    o.realistic = RealisticTruth{};
    o.realistic->noise_low_mm = 0.2;  // above noise_high_mm
  };
  const auto realistic_with_a_model = [](BlindtestOptions& o) {
    o.realistic = RealisticTruth{};
    o.realistic->noise_low_mm = 0.03;
    o.model = ModelDiagnoseOptions{};
  };
  EXPECT_TRUE(refuses<BlindtestOptions>(no_trials, "trials"));
  EXPECT_TRUE(refuses<BlindtestOptions>(unknown_effect, "gremlins"));
  EXPECT_TRUE(refuses<BlindtestOptions>(noise_range_reversed, "realistic.noise_low_mm"));
  EXPECT_TRUE(refuses<BlindtestOptions>(realistic_with_a_model, "realistic"));
}

}  // namespace
}  // namespace canalsim::diagnosis
