// Diagnosis against a calibrated baseline (diagnosis/baseline.hpp). The truth is the laboratory
// canal simulated differently (testing/realistic.hpp: four times the cells, the other limiter and
// Courant number) with its uncertain parameters off the scenario's values by a laboratory's
// tolerances (discharge coefficient, Manning n, downstream opening, a level offset). Clean baseline
// recordings of that truth calibrate the scenario; the recordings to diagnose come from the same
// truth, clean or with a concealed effect. Also: the [calibration.std] table that carries the
// calibrated deviations from `canalsim calibrate` to `canalsim diagnose`, and the checks that
// refuse a baseline of another logger or canal.
#include "diagnosis/baseline.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "calibration/scenario_file.hpp"
#include "diagnosis/blindtest.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/simulate.hpp"
#include "testing/realistic.hpp"
#include "tests/diagnosis/lab_recordings.hpp"

namespace canalsim::diagnosis {
namespace {

// The laboratory as it "really" is: another discretisation, and parameters off the scenario's.
scenarios::Scenario perturbed_truth() {
  scenarios::Scenario s = testing::independent_truth(scenarios::builtin_scenario("lab"));
  s.head_gate->discharge_coefficient *= 1.04;
  s.pools.front().manning_n *= 1.2;
  s.downstream.gate.opening_m += 0.8e-3;
  s.sensors.offset_y_dwe_mm = 0.4;
  return s;
}

std::vector<Recording> record(const std::vector<std::string>& experiments, const std::vector<ConcealedEffect>& effects,
                              std::uint64_t seed, const std::string& prefix) {
  const scenarios::Scenario truth = perturbed_truth();
  std::vector<Recording> out;
  for (const auto& name : experiments) {
    scenarios::Scenario s = truth;
    const scenarios::ExperimentSpec e = short_experiment(s, name, 120.0, s.sensors, 0.05, seed++);
    Recording r = simulate_concealed(s, e, effects, 0.0, settled_run(/*quiet=*/true));
    r.source = prefix + name + ".csv";
    out.push_back(std::move(r));
  }
  return out;
}

BaselineOptions fast_options() {
  BaselineOptions o;
  o.diagnosis.candidates = {"command_delay", "level_datum", "discharge_coefficient", "downstream_gate", "friction"};
  o.diagnosis.settle_time_s = kSettle;
  o.diagnosis.max_evaluations = 5;
  return o;
}

TEST(Baseline, CalibratedDiagnosisNamesAConcealedDelayAndCalibrationRemovesTheFalseAlarm) {
  const std::vector<Recording> baseline = record({"op1", "op3"}, {}, 21, "base_");
  const std::vector<Recording> clean = record({"op2", "op4"}, {}, 31, "");
  const std::vector<Recording> delayed = record({"op2", "op4"}, {{"command_delay", 1.0}}, 31, "");
  const BaselineOptions o = fast_options();

  // Against the scenario as given, the parameter mismatch alone looks like a fault.
  const Diagnosis uncalibrated = diagnose(scenarios::builtin_scenario("lab"), clean, o.diagnosis);
  ASSERT_TRUE(uncalibrated.ok) << uncalibrated.message;
  EXPECT_NE(uncalibrated.verdict, "none") << "the test's truth must be off the scenario: " << uncalibrated.reason;

  const BaselineDiagnosis r = diagnose_with_baseline(scenarios::builtin_scenario("lab"), baseline, clean, o);
  ASSERT_TRUE(r.calibration.ok) << r.calibration.message;
  ASSERT_TRUE(r.diagnosis.ok) << r.diagnosis.message;
  EXPECT_LT(r.calibration.cost_after, 0.5 * r.calibration.cost_before);
  EXPECT_EQ(r.baseline, (std::vector<std::string>{"base_op1.csv", "base_op3.csv"}));
  EXPECT_EQ(r.diagnosis.verdict, "none") << r.diagnosis.reason;
  EXPECT_LT(r.diagnosis.nominal_rms, uncalibrated.nominal_rms);
  // What the calibration left open goes to the diagnosis: a deviation for every parameter.
  const auto deviations = calibrated_std_of(r.calibration);
  EXPECT_EQ(deviations.size(), r.calibration.parameters.size());
  for (const auto& [name, sd] : deviations) EXPECT_GT(sd, 0.0) << name;

  // The two-step workflow on the same calibration (calibrate once, diagnose later recordings).
  DiagnoseOptions later = o.diagnosis;
  later.calibrated_std = deviations;
  const Diagnosis d = diagnose(r.calibration.calibrated, delayed, later);
  ASSERT_TRUE(d.ok) << d.message;
  EXPECT_EQ(d.verdict, "command_delay") << d.reason;
  EXPECT_LE(parameter_error({"command_delay", 1.0}, d.effects.front().parameter.value), 0.25);
}

// Two effects at once in recordings the diagnosis' model did not make: a 2 mm leak under the head
// gate and the downstream gate 1 mm lower. Both raise the levels, so each alone explains much of
// the other's residual; the verdict fitted alone absorbs part of the second effect, which then
// adds only what the first leaves. The joint fit (pipeline step 5) must name both, each within
// the blind test's 25 %, with their jointly refitted parameters. Measured: 2.13 and
// −0.951 mm; the pairs 1.0/−1.0, 1.5/−1.5 and 2.5/−0.7 mm pass too, 0.8/−0.6 mm names the gate
// only; on two recordings (op2, op4) instead of four the leak came out 28 % high.
TEST(Baseline, TwoEffectsConcealedInAnotherTruthAreBothNamedWithTheirJointParameters) {
  const std::vector<Recording> baseline = record({"op1", "op2", "op3", "op4"}, {}, 21, "base_");
  const std::vector<ConcealedEffect> concealed = {{"gate_leakage", 2.0}, {"downstream_gate", -1.0}};
  const std::vector<Recording> recordings = record({"op1", "op2", "op3", "op4"}, concealed, 31, "");
  BaselineOptions o = fast_options();
  o.diagnosis.candidates = {"gate_leakage", "downstream_gate", "discharge_coefficient", "level_datum", "friction"};
  const BaselineDiagnosis r = diagnose_with_baseline(scenarios::builtin_scenario("lab"), baseline, recordings, o);
  ASSERT_TRUE(r.diagnosis.ok) << r.diagnosis.message;
  const auto& explanation = r.diagnosis.explanation;
  for (const ConcealedEffect& effect : concealed) {
    const auto found = std::find_if(explanation.begin(), explanation.end(),
                                    [&](const ExplainedEffect& e) { return e.name == effect.effect; });
    ASSERT_NE(found, explanation.end()) << effect.effect << " not named; verdict " << r.diagnosis.verdict;
    EXPECT_LT(parameter_error(effect, found->parameter.value), 0.25)
        << effect.effect << ": concealed " << effect.value << ", found " << found->parameter.value;
    EXPECT_GT(found->share, 0.0) << effect.effect;
  }
}

TEST(Baseline, ABaselineOfAnotherLoggerOrCanalIsNamedWithTheDifference) {
  Recording rec, base;
  rec.source = "rec.csv";
  base.source = "base3.csv";
  std::vector<double> t13, t26, u;
  for (int k = 0; k < 60; ++k) {
    t13.push_back(0.13 * k);
    t26.push_back(0.26 * k);
    u.push_back(20.0);
  }
  rec.set_column("t_s", t13);
  base.set_column("t_s", t26);
  for (Recording* r : {&rec, &base}) {
    r->set_column("u_mm", u);
    r->set_column("y_dwe_mm", u);
  }
  auto problems = check_baseline({base}, {rec});
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems.front(), "base3.csv: sampled every 0.26 s, the recordings every 0.13 s");

  base.set_column("t_s", t13);
  base.set_meta("scenario", "asce1");
  rec.set_meta("scenario", "lab");
  problems = check_baseline({base}, {rec});
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_NE(problems.front().find("base3.csv: recorded on canal 'asce1', the recordings on 'lab'"), std::string::npos)
      << problems.front();
  EXPECT_THROW(diagnose_with_baseline(scenarios::builtin_scenario("lab"), {base}, {rec}, fast_options()), InputError);
  EXPECT_FALSE(check_baseline({}, {rec}).empty());

  // A recording at another operating point than the baseline's: warned, not refused.
  std::vector<double> u2(u.size(), 40.0);
  u2[5] = 45.0;
  rec.set_column("u_mm", u2);
  const auto warnings = baseline_coverage({base}, {rec});
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings.front(), "rec.csv: gate command 40..45 mm, the baseline covered 20..20 mm: the calibration may not hold there");
  rec.set_column("u_mm", u);
  EXPECT_TRUE(baseline_coverage({base}, {rec}).empty());
}

std::string lab_text() {
  for (const auto& b : scenarios::builtin_scenarios()) {
    if (b.name == "lab") return b.toml;
  }
  return "";
}

TEST(Baseline, TheCalibrationTableCarriesTheDeviationsAndIsCheckedLikeEveryKey) {
  const std::string text = lab_text();
  std::string calibrated = calibration::with_calibration_table(
      text, {{"cd_free", 0.012}, {"manning_n", 4e-4}, {"offset_y_dwe_mm", 0.03}, {"cd_submerged", INFINITY}});
  // Calibrated again: the new table replaces the old one.
  calibrated = calibration::with_calibration_table(calibrated, {{"cd_free", 0.02}, {"manning_n.1", 5e-4}}, 0.125);
  const scenarios::Scenario s = scenarios::parse_scenario(calibrated, "cal.toml");
  EXPECT_EQ(s.calibrated_std, (std::map<std::string, double>{{"cd_free", 0.02}, {"manning_n.1", 5e-4}}));
  EXPECT_EQ(s.calibrated_baseline_rms_mm, 0.125);
  EXPECT_EQ(scenarios::parse_scenario(lab_text(), "lab.toml").calibrated_baseline_rms_mm, 0.0);
  EXPECT_EQ(s.name, "lab");

  // manning_n.1 names a pool of a canal with several pools: not of the one-pool lab.
  try {
    calibrated_std_of(s);
    ADD_FAILURE() << "an unknown parameter was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cal.toml: calibration.std.manning_n.1: not a calibration parameter of lab"),
              std::string::npos)
        << e.what();
  }
  const std::string one = calibration::with_calibration_table(text, {{"cd_free", 0.02}, {"manning_n", 5e-4}});
  EXPECT_EQ(calibrated_std_of(scenarios::parse_scenario(one, "cal.toml")).at("manning_n"), 5e-4);

  const auto refused = [&](const std::string& table, const std::string& expected) {
    try {
      scenarios::parse_scenario(text + "\n" + table, "cal.toml");
      ADD_FAILURE() << table << ": accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused("[calibration.std]\ncd_free = -0.1\n", "calibration.std.cd_free = -0.1: expected a number in [0, 1e+06]");
  refused("[calibration.std]\ncd_free = \"small\"\n", "calibration.std.cd_free is a string");
  refused("[calibration]\nstdev = 1\n", "unknown key calibration.stdev");
  refused("[calibration]\nbaseline_rms_mm = -1\n", "calibration.baseline_rms_mm = -1: expected a number in [0, 1e+06] mm");
  refused("[calibration.std]\n\"Cd free\" = 0.1\n", "expected a calibration parameter name");
}

}  // namespace
}  // namespace canalsim::diagnosis
