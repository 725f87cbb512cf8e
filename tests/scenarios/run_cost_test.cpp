// The up-front cost estimate (scenarios/run_cost.hpp) against the real runs it predicts, and the
// end gate as the controlled one (docs/scenarios.md, `controlled`).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/run_cost.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::scenarios {
namespace {

// The estimate errs towards more steps (the celerity of a full pool) but stays within a small
// factor of the steps the solver really takes on the lab canal.
TEST(RunCost, TheEstimateBoundsTheRealStepsFromAbove) {
  const Scenario lab = builtin_scenario("lab");
  ExperimentSpec e = *lab.find_experiment("op1");
  e.duration_s = 60.0;
  const RunCost cost = estimate_run_cost(lab, e, lab.sensors.period_s);
  long steps = 0;
  SimulateOptions options;
  options.on_finish = [&steps](const BuiltCanal& b) { steps = b.canal.statistics().steps; };
  const Recording rec = simulate(lab, e, options);
  EXPECT_EQ(static_cast<double>(rec.size()), cost.samples);
  EXPECT_GT(steps, 0);
  EXPECT_GE(cost.time_steps, 1.0 * static_cast<double>(steps));
  EXPECT_LE(cost.time_steps, 4.0 * static_cast<double>(steps));
  EXPECT_DOUBLE_EQ(cost.cell_updates, cost.time_steps * 100.0);
}

TEST(RunCost, ARunAboveTheCeilingIsRefusedUnlessAllowed) {
  Scenario lab = builtin_scenario("lab");
  lab.pools.front().cells = 1000000;
  const ExperimentSpec& e = *lab.find_experiment("op1");
  EXPECT_THROW(check_run_cost(lab, e, 0.13, false), InputError);
  EXPECT_NO_THROW(check_run_cost(lab, e, 0.13, true));
  // Fewer than two samples, or more than 1e9, whatever the flag.
  EXPECT_THROW(check_run_cost(lab, e, 3600.0, true), InputError);
  EXPECT_THROW(check_run_cost(lab, e, 1e-9, true), InputError);
}

// calibrate and diagnose replay their recordings on --threads threads: the user waits for the
// work shared among the threads the recordings keep busy, so each has one run's ceiling.
TEST(RunCost, AJobOfSeveralRecordingsHasOneRunsCeilingOnEachThreadItKeepsBusy) {
  EXPECT_DOUBLE_EQ(replays_ceiling(2, 4), 2.0 * kMaxCellUpdates);
  EXPECT_DOUBLE_EQ(replays_ceiling(4, 2), 2.0 * kMaxCellUpdates);  // two recordings busy two threads
  EXPECT_DOUBLE_EQ(replays_ceiling(1, 4), kMaxCellUpdates);
  EXPECT_DOUBLE_EQ(replays_ceiling(2, 0), kMaxCellUpdates);
  EXPECT_EQ(replays_ceiling_text(2, 4), "6e+10 (3e+10 on each of 2 threads)");
  EXPECT_EQ(replays_ceiling_text(1, 4), "3e+10");
}

// A pool narrower than its gate by 80 times makes the flow ~80 times faster than the estimate's
// waves; the guard stops the run once its projected cost passes the ceiling.
TEST(RunCost, TheGuardStopsARunWhoseStepCollapses) {
  const Scenario lab = builtin_scenario("lab");
  const ExperimentSpec& e = *lab.find_experiment("op1");
  RunCostGuard guard(lab, e, false);
  guard.check(0, 0.0, 0.0);
  EXPECT_NO_THROW(guard.check(30000, 100.0, 0.003));  // 30000 steps for 100 of 255.5 s: ~5e6 updates
  // Then the step collapses: 20000 steps for 1 ms, 155 s to go -> ~3e11 updates.
  EXPECT_THROW(guard.check(50000, 100.001, 5e-8), InputError);
  RunCostGuard allowed(lab, e, true);
  allowed.check(0, 0.0, 0.0);
  EXPECT_NO_THROW(allowed.check(30000, 1e-3, 3e-8));
  RunCostGuard steady(lab, e, false);
  steady.check(0, 0.0, 0.0);
  for (long k = 1; k <= 10; ++k) EXPECT_NO_THROW(steady.check(20000 * k, 0.025 * 20000 * static_cast<double>(k), 0.025));
}

TEST(RunCost, TheEndGateCanBeDriven) {
  Scenario lab = builtin_scenario("lab");
  lab.head_gate->controlled = false;
  lab.head_gate->opening_m = 0.015;
  lab.downstream.gate.controlled = true;
  validate(lab);
  ExperimentSpec e = *lab.find_experiment("op1");
  e.duration_s = 30.0;
  e.operating_opening_mm = 20.0;
  const Recording rec = simulate(lab, e);
  const auto& u = rec.column(columns::gate_command);
  const auto& x = rec.column(columns::gate_position);
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  EXPECT_NEAR(*lo, 15.0, 1e-9);  // the PRBS, 20 ± 5 mm, on the end gate
  EXPECT_NEAR(*hi, 25.0, 1e-9);
  EXPECT_NEAR(x.back(), u.back(), 0.05);
  for (double q : rec.column(columns::discharge)) EXPECT_GT(q, 0.0);
}

}  // namespace
}  // namespace canalsim::scenarios
