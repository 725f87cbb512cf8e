// What a run will cost, known before it starts: an estimate of the solver's work (cells × time
// steps) and of the memory the recording takes, checked against documented ceilings so that an
// input that cannot run in reasonable time or memory (10⁶ cells, a 1e-9 s sampling period, 10⁷ s
// at CFL 0.001) is a one-line error instead of minutes of silence or std::bad_alloc
// (docs/scenarios.md, "Run cost").
#pragma once

#include <cstddef>
#include <string>

#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::scenarios {

struct RunCost {
  double samples = 0.0;       // rows of the recording
  double time_steps = 0.0;    // adaptive steps over settle_s + duration_s (estimate)
  double cell_updates = 0.0;  // cells × time steps
  double memory_bytes = 0.0;  // the recording and the solver state (estimate)
};

// Ceilings of one run: ~5 minutes of solver work at the ~100 M cell updates/s of the second-order
// step on one core (bench/README.md: 91 M/s on the laboratory canal's 100 cells, 105–151 M/s on
// 10³–10⁵ cells), and 2 GB. `--allow-long` (SimulateOptions::allow_long_run) goes past them.
inline constexpr double kMaxCellUpdates = 3.0e10;
inline constexpr double kMaxMemoryBytes = 2.0e9;
// The ceiling of a job that replays `recordings` independent recordings `threads` at a time
// (calibrate, diagnose): one run's ceiling on each thread the replays keep busy, since the user
// waits for the work shared among them.
double replays_ceiling(int threads, std::size_t recordings);
// "3e+10 (on each of 2 threads)": the ceiling as the refusals quote it.
std::string replays_ceiling_text(int threads, std::size_t recordings);
// Beyond this no flag helps: the sample count would not fit the index types.
inline constexpr double kMaxSamples = 1.0e9;

// The estimate. Time steps follow the CFL condition dt = cfl dx / (|u| + c) with the celerity
// c = sqrt(g h) of a pool filled to its wall height (the fastest wave a pool within its banks
// carries; |u| is of the same order in subcritical canals), so the estimate errs towards more steps;
// a PRBS input adds one step per clock period (each jump ends a step).
RunCost estimate_run_cost(const Scenario& scenario, const ExperimentSpec& experiment, double sample_period_s);

// One replay of `recording` through `scenario`: a run of the recording's duration sampled at its
// period. Calibration and diagnosis replay each recording many times; their callers multiply.
RunCost estimate_replay_cost(const Scenario& scenario, const Recording& recording);

// Throws InputError naming the scenario, experiment and keys when the run yields fewer than two
// samples, exceeds kMaxSamples, or (unless allow_long) exceeds a ceiling above.
void check_run_cost(const Scenario& scenario, const ExperimentSpec& experiment, double sample_period_s,
                    bool allow_long);

// The same ceiling checked as the run goes: a flow far faster than the estimate's waves (1e5 m³/s
// into a small canal, a pool 1e-6 m wide behind a 0.08 m gate) makes the time step collapse, and
// the run would go on for days with its progress line stuck; so does a pool an offtake drains.
// check() projects the work of the whole run from the pace of the last 20 000 steps and throws
// InputError (naming the time and the step) when it passes the ceiling, unless allow_long.
class RunCostGuard {
 public:
  RunCostGuard(const Scenario& scenario, const ExperimentSpec& experiment, bool allow_long);
  // Called after each step: the solver's step count so far, the time reached, the last step.
  // The first call sets the origin of the projection.
  void check(long steps, double time, double last_step);

 private:
  std::string where_;
  double cells_ = 0.0;
  double end_ = 0.0;
  bool allow_long_ = false;
  bool started_ = false;
  long first_steps_ = 0;
  long window_steps_ = 0;
  double window_time_ = 0.0;
};

}  // namespace canalsim::scenarios
