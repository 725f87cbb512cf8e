// Experiments on the built-in laboratory canal: the recording has the paper's format; the run
// starts from the steady state long time marching reaches; the calibrated canal shows the
// paper's flow regimes by condition (23); the gate-to-sensor delay is the gravity-wave travel
// time computed in closed form from the steady state; a drive recording is replayed.
#include "scenarios/simulate.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <string>

#include "gates/sluice_gate.hpp"
#include "scenarios/builtin.hpp"
#include "solver/steady_state.hpp"

namespace canalsim::scenarios {
namespace {

ExperimentSpec lab_experiment(double opening_mm, double duration_s, InputKind kind = InputKind::prbs) {
  ExperimentSpec e;
  e.name = "test";
  e.operating_opening_mm = opening_mm;
  e.duration_s = duration_s;
  e.input.kind = kind;
  return e;
}

TEST(Simulate, LabRecordingHasThePaperFormatAndResolution) {
  const Scenario lab = builtin_scenario("lab");
  const Recording rec = simulate(lab, lab_experiment(25.0, 30.0));
  ASSERT_EQ(rec.size(), 231u);  // 30 s / 0.13 s + 1
  EXPECT_NEAR(rec.sample_period(), 0.13, 1e-12);
  for (const char* c : {"t_s", "u_mm", "x_up_mm", "y_up_mm", "y_dw_mm", "y_dwe_mm", "q_lps", "regime", "y_lc_mm"}) {
    EXPECT_TRUE(rec.has(c)) << c;
  }
  for (double y : rec.column("y_dwe_mm")) {
    EXPECT_NEAR(y / 0.05, std::round(y / 0.05), 1e-6) << "eq. (17): multiples of 0.05 mm";
  }
  for (double u : rec.column("u_mm")) EXPECT_TRUE(u == 20.0 || u == 30.0) << "PRBS 25 ± 5 mm";
  EXPECT_NE(rec.meta("initial_state").find("Newton"), std::string::npos);
  // The regime column is condition (10) on the recorded columns: submerged iff y_up < y_lc.
  for (std::size_t k = 0; k < rec.size(); ++k) {
    const bool submerged = rec.column("y_up_mm")[k] <= rec.column("y_lc_mm")[k];
    EXPECT_EQ(rec.column("regime")[k], submerged ? 1.0 : 0.0) << "sample " << k;
  }
}

// A negative sensor delay (levels that lead the command, scenario key sensors.delay_s): every
// level column is the undelayed one two samples on, the command and discharge unchanged, and the
// last two samples hold the run's last level.
TEST(Simulate, LevelsThatLeadTheCommandAreTheSameRunSamplesEarlier) {
  Scenario lab = builtin_scenario("lab");
  const Recording plain = simulate(lab, lab_experiment(25.0, 30.0));
  lab.sensors.delay_s = -2 * 0.13;
  const Recording leading = simulate(lab, lab_experiment(25.0, 30.0));
  ASSERT_EQ(leading.size(), plain.size());
  EXPECT_EQ(leading.column("u_mm"), plain.column("u_mm"));
  EXPECT_EQ(leading.column("q_lps"), plain.column("q_lps"));
  const std::size_t n = plain.size();
  for (const char* c : {"y_up_mm", "y_dw_mm", "y_dwe_mm"}) {
    const auto& a = leading.column(c);
    const auto& b = plain.column(c);
    for (std::size_t k = 0; k + 2 < n; ++k) EXPECT_NEAR(a[k], b[k + 2], 1e-9) << c << " sample " << k;
    EXPECT_NEAR(a[n - 2], b[n - 1], 1e-9) << c;
    EXPECT_NEAR(a[n - 1], b[n - 1], 1e-9) << c;
  }
  // The PRBS moves the levels: the shift is seen.
  const auto& y = plain.column("y_dw_mm");
  EXPECT_GT(*std::max_element(y.begin(), y.end()) - *std::min_element(y.begin(), y.end()), 1.0);
}

TEST(Simulate, NewtonInitialStateIsTheOneTimeMarchingReaches) {
  // A fixed 60 mm supply: the reservoir's PID would only slow the marching down.
  Scenario lab = builtin_scenario("lab");
  lab.upstream.kind = UpstreamKind::level;
  const ExperimentSpec e = lab_experiment(25.0, 10.0, InputKind::constant);
  BuiltCanal newton = build_canal(lab, e), marching = build_canal(lab, e);
  newton.controlled->reset(0.0, 0.025);
  marching.controlled->reset(0.0, 0.025);
  ASSERT_TRUE(solver::solve_steady_state(newton.canal).status);
  ASSERT_TRUE(marching.canal.advance_to(1500.0));
  double worst = 0.0;
  for (int i = 0; i < newton.canal.reach(0).cells(); ++i) {
    worst = std::max(worst, std::abs(newton.canal.reach(0).depth(i) - marching.canal.reach(0).depth(i)));
  }
  EXPECT_LT(worst, 1e-8);
}

// settle_s marches before t = 0, unrecorded. With Newton off, 300 s of marching from the
// builder's flat start must land on Newton's steady state (the flume settles to 1e-8 m in ~52 s of
// flow, bench/README.md); 1 s of it must not, so the key is shown to be used.
TEST(Simulate, SettleTimeMarchesBeforeRecording) {
  Scenario lab = builtin_scenario("lab");
  lab.upstream.kind = UpstreamKind::level;
  ExperimentSpec e = lab_experiment(25.0, 1.0, InputKind::constant);
  const Recording newton = simulate(lab, e);
  SimulateOptions marching_only;
  marching_only.use_steady_state_solver = false;
  marching_only.settle_time = 0.0;
  auto first_q = [](const Recording& r) { return r.column("q_lps").front(); };
  auto first_y = [](const Recording& r) { return r.column("y_dwe_mm").front(); };
  e.settle_s = 300.0;
  const Recording settled = simulate(lab, e, marching_only);
  EXPECT_NEAR(first_q(settled), first_q(newton), 1e-6 * first_q(newton));
  EXPECT_NEAR(first_y(settled), first_y(newton), 0.051);  // one 0.05 mm quantum at most
  EXPECT_NE(settled.meta("initial_state").find("time marching 300 s"), std::string::npos);
  e.settle_s = 1.0;
  const Recording short_settle = simulate(lab, e, marching_only);
  EXPECT_GT(std::abs(first_q(short_settle) - first_q(newton)), 0.01 * first_q(newton));
}

// Without Newton (off, or failed as with minmod on fine grids) the marching that replaces it stops
// once the canal has settled instead of running all of settle_time (600 s; measured 270 s here):
// the PRBS recording that follows is the one Newton's steady state starts, to far below the
// sensor's resolution.
TEST(Simulate, MarchingInPlaceOfNewtonStopsOnceTheCanalHasSettled) {
  Scenario lab = builtin_scenario("lab");  // with its reservoir and PID, as the experiments run
  lab.sensors.resolution_mm = 0.0;
  // A 2 m² upstream pool (50 times the lab's) settles slowly, so a premature stop would show:
  // stopped at 90 s, the recording is 5.7e-3 mm RMS off; settled, 8e-7 mm (measured).
  lab.upstream.plan_area_m2 = 2.0;
  const ExperimentSpec e = lab_experiment(25.0, 30.0);
  const Recording newton = simulate(lab, e);
  SimulateOptions marching_only;
  marching_only.use_steady_state_solver = false;
  const Recording marched = simulate(lab, e, marching_only);
  const std::string how = marched.meta("initial_state");
  ASSERT_EQ(how.rfind("time marching ", 0), 0u) << how;
  const double seconds = std::stod(how.substr(std::string("time marching ").size()));
  EXPECT_LT(seconds, 0.5 * marching_only.settle_time) << how;
  for (const char* c : {"y_dw_mm", "y_dwe_mm", "y_up_mm"}) {
    double sum = 0.0;
    const auto& a = newton.column(c);
    const auto& b = marched.column(c);
    for (std::size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
    EXPECT_LT(std::sqrt(sum / static_cast<double>(a.size())), 1e-4) << c << " [mm RMS], after " << seconds << " s";
  }
}

// Two runs of one experiment that started from the same state by different routes (Newton, a
// stall, a march): every level and the discharge agree to well within the sensor's 0.05 mm.
void expect_same_levels_and_discharge(const Recording& a, const Recording& b) {
  for (const char* c : {"y_dw_mm", "y_dwe_mm", "y_up_mm", "q_lps"}) {
    double worst = 0.0;
    const auto& x = a.column(c);
    const auto& y = b.column(c);
    for (std::size_t k = 0; k < x.size(); ++k) worst = std::max(worst, std::abs(x[k] - y[k]));
    EXPECT_LT(worst, 1e-3) << c << " (mm or L/s)";
  }
}

// With minmod on 400 cells Newton stalls at the limiter's kinks (docs/numerics.md). The stall is
// accepted when it is as settled as the march that would replace it, and the recording it starts
// must be the one that march starts — before the input begins: a continuation retry that marched
// under the PRBS's first commands would start op1 at 0.61 L/s instead of 0.476.
// Measured: the two recordings differ by at most 2.4e-6 mm (y_dwe) and 2.4e-8 L/s.
TEST(Simulate, AStalledSteadyStateStartsWhereTheMarchWould) {
  Scenario lab = builtin_scenario("lab");
  lab.sensors.resolution_mm = 0.0;
  lab.pools.front().cells = 400;
  lab.numerics.van_leer_limiter = false;
  const ExperimentSpec e = lab_experiment(15.0, 20.0);
  const Recording stalled = simulate(lab, e);
  ASSERT_NE(stalled.meta("initial_state").find("stalled"), std::string::npos) << stalled.meta("initial_state");
  SimulateOptions marching_only;
  marching_only.use_steady_state_solver = false;
  const Recording marched = simulate(lab, e, marching_only);
  expect_same_levels_and_discharge(stalled, marched);
  // The operating point's discharge, not the first command's: van Leer's Newton converges there.
  Scenario van_leer = lab;
  van_leer.numerics.van_leer_limiter = true;
  const double operating = simulate(van_leer, e).column("q_lps").front();
  EXPECT_NEAR(stalled.column("q_lps").front(), operating, 1e-4 * operating);
}

// Where minmod's first Newton fails outright — the lab's op2 on 400 cells with the calibration
// tests' six parameters perturbed: "the line search could not reduce the residual" after 2
// iterations from the design guess, then 60 iterations after each continuation march, and the
// run started after 60 s of marching with a warning — the steady state is found through van
// Leer's (solver/steady_state.cpp, limiter homotopy), and it is the state marching settles on.
TEST(Simulate, MinmodsSteadyStateIsFoundThroughVanLeersWhereItsOwnNewtonFails) {
  Scenario lab = builtin_scenario("lab");
  lab.sensors.resolution_mm = 0.0;
  lab.pools.front().cells = 400;
  lab.numerics.van_leer_limiter = false;
  lab.numerics.cfl = 0.45;
  lab.head_gate->discharge_coefficient = 0.9;
  lab.head_gate->submerged_discharge_coefficient = 1.1;
  lab.pools.front().manning_n *= 1.5;
  lab.downstream.gate.opening_m += 1e-3;
  const ExperimentSpec e = lab_experiment(25.0, 20.0);
  std::vector<std::string> warnings;
  SimulateOptions collect;
  collect.warning = [&warnings](const std::string& w) { warnings.push_back(w); };
  const Recording solved = simulate(lab, e, collect);
  EXPECT_TRUE(warnings.empty()) << (warnings.empty() ? "" : warnings.front());
  ASSERT_EQ(solved.meta("initial_state").rfind("steady state (Newton", 0), 0u) << solved.meta("initial_state");
  SimulateOptions marching_only;
  marching_only.use_steady_state_solver = false;
  const Recording marched = simulate(lab, e, marching_only);
  expect_same_levels_and_discharge(solved, marched);
}

// The paper's condition (23) at the operating point (steady state, constant input).
gates::GateRegime regime_at(double opening_mm) {
  const Scenario lab = builtin_scenario("lab");
  const Recording rec = simulate(lab, lab_experiment(opening_mm, 1.0, InputKind::constant));
  return gates::classify_regime(rec.column("y_up_mm").back() * 1e-3,
                                rec.column("y_dwe_mm").back() * 1e-3, opening_mm * 1e-3);
}

TEST(Simulate, LabCanalHasThePapersRegimesAtItsOperatingPoints) {
  EXPECT_EQ(regime_at(13.0), gates::GateRegime::submerged);  // op1*
  EXPECT_EQ(regime_at(15.0), gates::GateRegime::submerged);  // op1
  EXPECT_EQ(regime_at(25.0), gates::GateRegime::submerged);  // op2
  EXPECT_EQ(regime_at(30.0), gates::GateRegime::submerged);  // the border lies above 30 mm
  EXPECT_EQ(regime_at(38.0), gates::GateRegime::free);       // ... and below 38 mm
  EXPECT_EQ(regime_at(43.0), gates::GateRegime::free);       // op3
  EXPECT_EQ(regime_at(45.0), gates::GateRegime::free);       // op4
}

TEST(Simulate, GateToSensorDelayIsTheGravityWaveTravelTime) {
  // A 5 mm step at t = 10 s reaches the downstream sensor after L / (u + c), with u and
  // c = sqrt(g h) of the steady pool (closed form; the paper identifies 4.9 s).
  const Scenario lab = builtin_scenario("lab");
  ExperimentSpec e = lab_experiment(25.0, 25.0, InputKind::step);
  e.input.start_s = 10.0;
  e.sensors = lab.sensors;
  e.sensors->resolution_mm = 0.0;
  const Recording rec = simulate(lab, e);
  const auto& y = rec.column("y_dwe_mm");
  const double h = y.front() * 1e-3;
  const double u = rec.column("q_lps").front() * 1e-3 / (0.08 * h);
  const double expected = lab.pools.front().length_m / (u + std::sqrt(9.81 * h));
  double arrival = -1.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    if (std::abs(y[k] - y.front()) > 0.5) {  // half-way up the ~1 mm front
      arrival = rec.column("t_s")[k] - 10.0;
      break;
    }
  }
  EXPECT_NEAR(arrival, expected, 0.1 * expected);
  EXPECT_NEAR(arrival, 4.9, 0.5);
}

TEST(Simulate, DriveRecordingIsReplayed) {
  // A step that switches on a sample instant: the replayed (zero-order-hold) command is then the
  // same signal, so the run is the same, from the same operating point (the metadata's).
  const Scenario lab = builtin_scenario("lab");
  ExperimentSpec step = lab_experiment(25.0, 20.0, InputKind::step);
  step.input.start_s = 20 * 0.13;
  const Recording first = simulate(lab, step);
  SimulateOptions options;
  options.drive.recording = &first;
  const Recording replay = simulate(lab, lab_experiment(35.0, 20.0), options);  // its own input ignored
  EXPECT_EQ(replay.column("u_mm"), first.column("u_mm"));
  EXPECT_EQ(replay.column("y_dwe_mm"), first.column("y_dwe_mm"));
}

// The gate leaves when its command does: with the constant-speed actuator of eq. (16), the
// opening a sample after a step of the command that falls between samples (and between solver
// steps) is the operating opening plus speed × elapsed time, exactly, and before it, unmoved.
// A gate that switched at the first solver step after the command would lag by up to
// a step: 40 ms on the lab's 100 cells, 0.2 mm of travel here.
TEST(Simulate, AGateDrivenThroughItsActuatorLeavesWhenItsCommandSteps) {
  Scenario lab = builtin_scenario("lab");
  lab.head_gate->actuator_speed_m_s = 0.005;  // 5 mm/s
  lab.sensors.resolution_mm = 0.0;
  ExperimentSpec step = lab_experiment(25.0, 3.0, InputKind::step);
  step.input.start_s = 1.05;  // between the samples at 1.04 and 1.17 s
  step.input.amplitude_mm = 10.0;  // still travelling at the end (3.05 s)
  const Recording rec = simulate(lab, step);
  const auto& t = rec.column("t_s");
  const auto& x = rec.column("x_up_mm");
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double expected = 25.0 + std::max(5.0 * (t[k] - 1.05), 0.0);
    EXPECT_NEAR(x[k], expected, 1e-6) << "t = " << t[k];
  }
}

TEST(Simulate, ScenarioWithoutAControlledGateIsRejected) {
  Scenario lab = builtin_scenario("lab");
  lab.head_gate->controlled = false;
  EXPECT_THROW(simulate(lab, lab_experiment(25.0, 5.0)), InputError);
}

// numerics.limiter_theta reaches the solver: the monotonised central limiter (θ = 2) clips the
// PRBS fronts less than minmod (θ = 1), so the two recordings differ, by far less than the fronts.
TEST(Simulate, TheMinmodParameterThetaReachesTheSolver) {
  Scenario lab = builtin_scenario("lab");
  lab.sensors.resolution_mm = 0.0;
  lab.numerics.van_leer_limiter = false;
  const ExperimentSpec e = lab_experiment(25.0, 20.0);
  const Recording minmod = simulate(lab, e);
  lab.numerics.limiter_theta = 2.0;
  const Recording mc = simulate(lab, e);
  double sum = 0.0;
  const auto& a = minmod.column("y_dwe_mm");
  const auto& b = mc.column("y_dwe_mm");
  for (std::size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  const double rms = std::sqrt(sum / static_cast<double>(a.size()));
  EXPECT_GT(rms, 1e-3);
  EXPECT_LT(rms, 1.0);
}

}  // namespace
}  // namespace canalsim::scenarios
