// Replays (calibration/replay.hpp): a recording replayed through the scenario that made it comes
// back as recorded; the replay starts where the recording says it starts.
#include "calibration/replay.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "calibration/problem.hpp"
#include "scenarios/variation.hpp"

#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::calibration {
namespace {

using scenarios::Scenario;

Scenario short_lab() {
  Scenario s = scenarios::builtin_scenario("lab");
  s.pools.front().cells = 40;
  return s;
}

Recording record(const Scenario& s, const std::string& experiment, double seconds) {
  scenarios::ExperimentSpec e = *s.find_experiment(experiment);
  e.duration_s = seconds;
  return scenarios::simulate(s, e);
}

double rms_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(sum / static_cast<double>(a.size()));
}

// `below_gate_mm`: the tolerance of y_dw, next to the gate, where a replayed upstream level
// brings its own 0.05 mm quantisation into the hydraulics.
void expect_replay_reproduces(const ReplayOptions& o, double below_gate_mm) {
  const Scenario s = short_lab();
  const Recording rec = record(s, "op2", 60.0);
  const Replay r = prepare_replay(rec, s, o);
  const Channels truth = replay_true(s, r, o);
  const Channels seen = observe(truth, sensor_model_of(s.sensors), r.period_s);
  // Levels within about one quantisation step (0.05 mm).
  EXPECT_LT(rms_difference(r.data.at(columns::level_downstream_end), seen.at(columns::level_downstream_end)), 0.05);
  EXPECT_LT(rms_difference(r.data.at(columns::level_below_gate), seen.at(columns::level_below_gate)), below_gate_mm);
}

// A PRBS-like command on a clock of `period` s starting at `phase` s, sampled every 0.13 s
// (right-continuous: the sample at a switch instant shows the new value).
void sampled_clocked_command(double period, double phase, std::vector<double>& t, std::vector<double>& u) {
  std::uint32_t lfsr = 0x1ACEu;
  std::vector<double> bits;
  for (int m = 0; m < 600; ++m) {
    lfsr = (lfsr >> 1) ^ (-(lfsr & 1u) & 0xB400u);  // 16-bit Galois LFSR
    bits.push_back((lfsr & 1u) ? 20.0 : 10.0);
  }
  for (int k = 0; k < 1966; ++k) {
    t.push_back(0.13 * k);
    const double m = std::floor((0.13 * k - phase) / period + 1e-12);
    u.push_back(bits[static_cast<std::size_t>(std::max(0.0, m))]);
  }
}

// The lab's 0.5 s clock started with the 0.13 s samples: every 6.5 s a switch falls on a sample
// instant, and the clock is found exactly — not at the centre of the clocks consistent with the
// samples, 5 ms early (replayed there, the level below the gate is 0.13 mm RMS off).
TEST(Replay, AClockStartedWithTheSamplesIsFoundExactly) {
  std::vector<double> t, u;
  sampled_clocked_command(0.5, 0.0, t, u);
  const std::vector<double> s = command_switch_times(t, u);
  ASSERT_FALSE(s.empty());
  int on_samples = 0;
  for (double x : s) {
    EXPECT_NEAR(x, 0.5 * std::round(x / 0.5), 1e-9) << x;
    if (std::abs(x / 0.13 - std::round(x / 0.13)) < 1e-6) ++on_samples;
  }
  EXPECT_GT(on_samples, 10);
}

// A clock that did not start with the samples (phase 0.2371 s), though commensurate with them,
// is left at the centre of the consistent clocks: not put on sample instants, and within a
// tenth of a sample of the truth.
TEST(Replay, AClockUnrelatedToTheSamplesStaysAtTheCentreOfItsPatch) {
  std::vector<double> t, u;
  sampled_clocked_command(0.5, 0.2371, t, u);
  const std::vector<double> s = command_switch_times(t, u);
  ASSERT_FALSE(s.empty());
  for (double x : s) {
    const double truth = 0.2371 + 0.5 * std::round((x - 0.2371) / 0.5);
    EXPECT_NEAR(x, truth, 0.013) << x;
    EXPECT_GT(std::abs(x / 0.13 - std::round(x / 0.13)), 1e-6) << x;
  }
}

TEST(Replay, ReproducesTheRecordingOfItsOwnScenario) { expect_replay_reproduces(ReplayOptions{}, 0.05); }

TEST(Replay, ReproducesItWithTheRecordedUpstreamLevelAndTheClock) {
  ReplayOptions o;
  o.use_recorded_upstream = true;
  o.clock_with_upstream = true;
  o.start_at_recorded_level = true;
  o.warmup_s = 0.0;
  expect_replay_reproduces(o, 0.08);
}

TEST(Replay, StartsFromTheSteadyStateAtTheRecordingsOwnUpstreamLevel) {
  // Recorded with the upstream pool held at 63 mm; the scenario says 60 mm.
  Scenario recorded_on = short_lab();
  recorded_on.upstream.level_m = 0.063;
  recorded_on.sensors.resolution_mm = 0.0;
  const Recording rec = record(recorded_on, "op3", 20.0);
  Scenario model = short_lab();
  model.sensors.resolution_mm = 0.0;
  ReplayOptions o;
  o.warmup_s = 0.0;
  const Replay r = prepare_replay(rec, model, o);
  // y_up reads the level at the gate, a few hundredths of a millimetre below the pool's.
  EXPECT_NEAR(r.initial_upstream_mm, 63.0, 0.05);
  const double first = r.data.at(columns::level_downstream_end).front();
  const double nominal = replay_true(model, r, o).at(columns::level_downstream_end).front();
  o.start_at_recorded_level = true;
  const double own = replay_true(model, r, o).at(columns::level_downstream_end).front();
  EXPECT_GT(std::abs(nominal - first), 0.5);   // 3 mm more head moves the steady level
  EXPECT_NEAR(own, first, 0.05);               // the same steady state as the recording's
}

TEST(Replay, InitialLevelMetadataOverridesTheFirstSamples) {
  Recording rec = record(short_lab(), "op3", 20.0);
  rec.set_meta("initial_y_up_mm", "61.5");
  EXPECT_DOUBLE_EQ(prepare_replay(rec, short_lab(), ReplayOptions{}).initial_upstream_mm, 61.5);
}

// A refined calibration starts where the coarser one's grid check simulated (calibrate.cpp,
// Handover): the simulations one problem made of another's scenario, handed over, give the same
// prediction at its start as its own simulations would, without simulating again.
TEST(ReplayProblem, SimulationsHandedOverAreReusedAtTheStart) {
  const Scenario coarse = short_lab();
  const std::vector<Recording> recordings{record(coarse, "op2", 30.0)};
  const std::vector<std::string> specs{"cd_free", "offset_y_dw_mm"};
  ReplayProblem on_coarse(coarse, select_parameters(coarse, specs), recordings, ReplayOptions{}, 1);
  const Scenario fine = scenarios::with_cells_multiplied(coarse, 2);
  std::vector<Channels> handed = on_coarse.simulate_all(fine);
  EXPECT_EQ(on_coarse.simulations(), 1);

  ReplayProblem primed(fine, select_parameters(fine, specs), recordings, ReplayOptions{}, 1);
  ReplayProblem fresh(fine, select_parameters(fine, specs), recordings, ReplayOptions{}, 1);
  primed.prime_start(std::move(handed));
  const std::vector<Channels> reused = primed.predict(primed.start());
  const std::vector<Channels> simulated = fresh.predict(fresh.start());
  EXPECT_EQ(primed.simulations(), 0);
  EXPECT_EQ(fresh.simulations(), 1);
  for (const auto& [channel, y] : simulated.front()) {
    ASSERT_TRUE(reused.front().count(channel)) << channel;
    EXPECT_LT(rms_difference(reused.front().at(channel), y), 1e-9) << channel;
  }
  // Away from the start, the primed problem simulates.
  std::vector<double> z = primed.start();
  z[0] += 0.01;
  primed.predict(z);
  EXPECT_EQ(primed.simulations(), 1);
}

// Levenberg–Marquardt takes the Jacobian at its current point, then evaluates candidates; when the
// last ones fail, the statistics ask again for the prediction at that point. It is kept apart from
// the candidates' (problem.cpp, truth_at): the same prediction as simulating afresh, no simulation.
TEST(ReplayProblem, ThePredictionWhereTheJacobianWasTakenOutlivesLaterCandidates) {
  const Scenario s = short_lab();
  const std::vector<Recording> recordings{record(s, "op2", 30.0)};
  const std::vector<std::string> specs{"cd_free", "offset_y_dw_mm"};
  ReplayProblem problem(s, select_parameters(s, specs), recordings, ReplayOptions{}, 1);
  ReplayProblem fresh(s, select_parameters(s, specs), recordings, ReplayOptions{}, 1);
  std::vector<double> z = problem.start();
  z[0] += 0.02;
  const std::vector<double> r = problem.residuals(problem.predict(z));
  problem.jacobian(z, r);
  const int after_jacobian = problem.simulations();
  EXPECT_EQ(after_jacobian, 2);  // the point, and cd_free's step (the offset only re-observes)
  for (double candidate : {0.05, -0.04}) {  // two candidates, each simulated
    std::vector<double> away = z;
    away[0] += candidate;
    problem.predict(away);
  }
  EXPECT_EQ(problem.simulations(), after_jacobian + 2);
  const std::vector<Channels> again = problem.predict(z);
  EXPECT_EQ(problem.simulations(), after_jacobian + 2);
  const std::vector<Channels> simulated = fresh.predict(z);
  for (const auto& [channel, y] : simulated.front()) {
    ASSERT_TRUE(again.front().count(channel)) << channel;
    EXPECT_LT(rms_difference(again.front().at(channel), y), 1e-12) << channel;
  }
}

// Secant Jacobians (ReplayProblem::use_secant_updates): the Jacobian at a new point costs no
// simulation and satisfies Broyden's secant condition J (z1 − z0) = r(z1) − r(z0) exactly, its
// sensor-only column is the differenced one (a re-observation, exact for an offset: −sqrt(w) per
// mm), and with secant updates off the same point is differenced again.
TEST(ReplayProblem, ASecantJacobianMatchesTheStepItWasUpdatedBy) {
  const Scenario s = short_lab();
  const std::vector<Recording> recordings{record(s, "op2", 30.0)};
  const std::vector<std::string> specs{"cd_free", "manning_n", "offset_y_dw_mm"};
  ReplayProblem problem(s, select_parameters(s, specs), recordings, ReplayOptions{}, 1);
  problem.use_secant_updates(true);
  const std::vector<double> z0 = problem.start();
  const std::vector<double> r0 = problem.residuals(problem.predict(z0));
  const std::vector<double> J0 = problem.jacobian(z0, r0);
  EXPECT_EQ(problem.simulations(), 3);  // the point, cd_free's and manning_n's steps
  std::vector<double> z1 = z0;
  z1[0] += 0.03;
  z1[1] -= 0.02;
  z1[2] += 0.1;
  const std::vector<double> r1 = problem.residuals(problem.predict(z1));
  const std::vector<double> J1 = problem.jacobian(z1, r1);
  EXPECT_EQ(problem.simulations(), 4);  // the new point only
  const std::size_t p = specs.size();
  double worst = 0.0, change = 0.0;
  for (std::size_t k = 0; k < r0.size(); ++k) {
    double predicted = 0.0;
    for (std::size_t j = 0; j < p; ++j) predicted += J1[k * p + j] * (z1[j] - z0[j]);
    worst = std::max(worst, std::abs(predicted - (r1[k] - r0[k])));
    change = std::max(change, std::abs(r1[k] - r0[k]));
  }
  EXPECT_GT(change, 1e-3);
  EXPECT_LT(worst, 1e-12 * change + 1e-15);
  // The offset's column: where the level below the gate is compared, −sqrt(w) per mm, elsewhere 0.
  const double minus_sqrt_w = -std::sqrt(problem.weights().weight.at(columns::level_below_gate));
  int offset_rows = 0;
  for (std::size_t k = 0; k < r0.size(); ++k) {
    const double d = J1[k * p + 2];
    if (d != 0.0) {
      ++offset_rows;
      EXPECT_NEAR(d, minus_sqrt_w, 1e-6 * std::abs(minus_sqrt_w));
    }
  }
  EXPECT_EQ(static_cast<std::size_t>(offset_rows), problem.replays().front().n_fit);
  // Off: the same point differenced (two hydraulic steps), then kept.
  problem.use_secant_updates(false);
  problem.jacobian(z1, r1);
  EXPECT_EQ(problem.simulations(), 6);
  problem.jacobian(z1, r1);
  EXPECT_EQ(problem.simulations(), 6);
}

}  // namespace
}  // namespace canalsim::calibration
