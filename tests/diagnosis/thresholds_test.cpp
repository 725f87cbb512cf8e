// Detection thresholds (pipeline.hpp step 7, diagnosis/thresholds.cpp) mean what they say: an
// effect at twice its reported threshold is named, at half of it is not. The truth is one the
// model cannot represent exactly (four times the cells, the other limiter, a discharge coefficient
// 3 % off and a downstream gate 0.6 mm off), so that the thresholds stand on a real model error,
// not on the materiality floor alone. Its recordings are simulated once with ideal sensors; each
// trial is what a logger writes of them with one instrument fault and its own noise
// (blindtest.hpp as_logged). Against a calibration the same holds for an outflow, on a truth of
// another scheme (the second simulator) that the calibration cannot represent exactly, and for a
// rougher bed below the catalog's smallest change of interest.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "calibration/calibrate.hpp"
#include "diagnosis/baseline.hpp"
#include "diagnosis/blindtest.hpp"
#include "diagnosis/diagnose.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"
#include "scenarios/staggered.hpp"
#include "testing/realistic.hpp"
#include "tests/diagnosis/lab_recordings.hpp"

namespace canalsim::diagnosis {
namespace {

std::vector<Recording> ideal_truth_recordings() {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  scenarios::Scenario truth = testing::independent_truth(lab);
  truth.head_gate->discharge_coefficient *= 1.03;
  truth.downstream.gate.opening_m += 0.6e-3;
  std::vector<Recording> out;
  for (const char* name : {"op1", "op3"}) {
    scenarios::SensorSpec ideal = lab.sensors;
    ideal.resolution_mm = 0.0;
    const scenarios::ExperimentSpec e = short_experiment(lab, name, 100.0, ideal, 0.0, ideal.seed);
    Recording r = scenarios::simulate(truth, e, settled_run(/*quiet=*/true));
    r.source = std::string(name) + ".csv";
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<Recording> logged(const std::vector<Recording>& ideal, const std::vector<ConcealedEffect>& faults,
                              std::uint64_t seed) {
  std::vector<Recording> out;
  for (const Recording& r : ideal) {
    Recording l = as_logged(r, faults, {0.05, 0.05, seed++});
    l.source = r.source;
    out.push_back(std::move(l));
  }
  return out;
}

// The parameter `factor` times as far from "no effect" as the threshold, on the side it reports.
double scaled(const DetectionThreshold& t, double factor) {
  const Effect e = *effect_from_name(t.effect);
  const double side = std::isfinite(t.above) ? t.above : t.below;
  const double none = e.kind->theta_none;
  return to_parameter(e, none + factor * (to_theta(e, side) - none));
}

TEST(Thresholds, AnEffectAtTwiceItsThresholdIsNamedAndAtHalfItIsNot) {
  const std::vector<Recording> ideal = ideal_truth_recordings();
  const std::vector<std::string> candidates = {"sensor_offset[y_dwe_mm]", "sensor_drift[y_up_mm]", "sensor_scale[y_dw_mm]",
                                               "sensor_delay[y_dwe_mm]", "command_delay"};
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  const Diagnosis clean = diagnose(lab, logged(ideal, {}, 101), among(candidates));
  ASSERT_TRUE(clean.ok) << clean.message;
  ASSERT_EQ(clean.thresholds.size(), candidates.size());
  int twice_named = 0, half_named = 0, trials = 0;
  std::uint64_t seed = 200;
  for (const DetectionThreshold& t : clean.thresholds) {
    ASSERT_TRUE(std::isfinite(t.above) || std::isfinite(t.below)) << t.effect;
    const Effect e = *effect_from_name(t.effect);
    std::cout << "[ thresholds ] " << t.effect << " " << t.below << " / " << t.above << " " << t.unit << " (material "
              << e.kind->material << ")\n";
    for (int k = 0; k < 2; ++k, seed += 10) {
      const Diagnosis twice = diagnose(lab, logged(ideal, {{t.effect, scaled(t, 2.0)}}, seed), among(candidates));
      const Diagnosis half = diagnose(lab, logged(ideal, {{t.effect, scaled(t, 0.5)}}, seed + 5), among(candidates));
      twice_named += twice.verdict == t.effect;
      half_named += half.verdict == t.effect;
      ++trials;
      EXPECT_EQ(twice.verdict, t.effect) << "at " << scaled(t, 2.0) << " " << t.unit << ": " << twice.reason;
    }
  }
  EXPECT_GE(twice_named, 0.9 * trials) << twice_named << " of " << trials;
  EXPECT_LE(half_named, 0.2 * trials) << half_named << " of " << trials;
  std::cout << "[ thresholds ] twice named " << twice_named << "/" << trials << ", half named " << half_named << "/"
            << trials << '\n';
}

// Recordings of op1 and op3 by the second simulator, the gate's discharge coefficient 3 % above
// the scenario's and the downstream gate 0.6 mm wider, with the concealed effects; `prbs` offsets
// the command's seed (a baseline runs another PRBS than the recordings diagnosed).
std::vector<Recording> second_simulator(const std::vector<ConcealedEffect>& concealed, std::uint64_t prbs, std::uint64_t seed) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  scenarios::Scenario truth = lab;
  truth.head_gate->discharge_coefficient *= 1.03;
  truth.downstream.gate.opening_m += 0.6e-3;
  std::vector<Recording> out;
  for (const char* name : {"op1", "op3"}) {
    scenarios::ExperimentSpec e = short_experiment(lab, name, 120.0, lab.sensors, 0.05, seed++);
    e.input.prbs_seed += prbs;
    Recording r = simulate_concealed(truth, e, concealed, steady_inflow_m3s(lab, e), settled_run(/*quiet=*/true),
                                     scenarios::staggered_simulator());
    r.source = std::string(name) + ".csv";
    out.push_back(std::move(r));
  }
  return out;
}

// Three draws of the sensors' noise at each factor: `effect` at twice its threshold (reported on
// clean recordings against the calibration) is named in all three, at half of it in none.
void expect_twice_named_and_half_not(const calibration::Calibration& calibrated, const DiagnoseOptions& against,
                                     const DetectionThreshold& t) {
  int twice_named = 0, half_named = 0;
  for (std::uint64_t seed = 500; seed < 530; seed += 10) {
    for (const double factor : {2.0, 0.5}) {
      const Diagnosis d =
          diagnose(calibrated.calibrated, second_simulator({{t.effect, scaled(t, factor)}}, 0, seed), against);
      ASSERT_TRUE(d.ok) << d.message;
      std::cout << "[ thresholds ] " << t.effect << " at " << factor << " x: " << d.verdict << ": " << d.reason << "\n";
      (factor > 1.0 ? twice_named : half_named) += d.verdict == t.effect;
    }
  }
  EXPECT_EQ(twice_named, 3) << t.effect;
  EXPECT_EQ(half_named, 0) << t.effect;
}

// Against a calibration the thresholds stand on the calibrated model's own error, not on the
// catalog's smallest change of interest: a rougher bed is revealed well below the catalog's floor
// (|ln m| >= 0.3, which stands for what an uncalibrated scenario may be off by).
TEST(Thresholds, AgainstACalibrationAnOutflowOrARougherBedAtTwiceItsThresholdIsNamedAndAtHalfItIsNot) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  BaselineOptions o;
  o.diagnosis = among({"lateral_outflow", "gate_leakage", "friction", "sensor_offset[y_dwe_mm]", "sensor_scale[y_dwe_mm]"});
  const calibration::Calibration calibrated =
      calibration::calibrate(lab, second_simulator({}, 1000, 300), {}, baseline_calibration_options(o));
  ASSERT_TRUE(calibrated.ok) << calibrated.message;
  const DiagnoseOptions against = against_calibration(calibrated, o.diagnosis);
  const Diagnosis clean = diagnose(calibrated.calibrated, second_simulator({}, 0, 400), against);
  ASSERT_TRUE(clean.ok) << clean.message;
  EXPECT_EQ(clean.verdict, "none") << clean.reason;
  const auto threshold = [&](const std::string& effect) {
    const auto t = std::find_if(clean.thresholds.begin(), clean.thresholds.end(),
                                [&](const DetectionThreshold& x) { return x.effect == effect; });
    const double none = std::numeric_limits<double>::quiet_NaN();
    return t != clean.thresholds.end() ? *t : DetectionThreshold{effect, "", "", none, none};
  };
  const DetectionThreshold outflow = threshold("lateral_outflow"), friction = threshold("friction");
  ASSERT_TRUE(std::isfinite(outflow.above));
  ASSERT_TRUE(std::isfinite(friction.above));
  std::cout << "[ thresholds ] against the calibration: lateral_outflow " << outflow.above << ", friction "
            << friction.above << "\n";
  const Effect rougher = *effect_from_name("friction");
  EXPECT_LT(to_theta(rougher, friction.above), 0.5 * rougher.kind->material) << "friction's threshold " << friction.above;
  expect_twice_named_and_half_not(calibrated, against, outflow);
  expect_twice_named_and_half_not(calibrated, against, friction);
}

}  // namespace
}  // namespace canalsim::diagnosis
