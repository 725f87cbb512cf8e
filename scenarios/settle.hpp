#pragma once
// The canal brought to rest at its operating point before an experiment starts (simulate()'s
// first phase): Newton's steady state on the discretised equations, then unrecorded time
// marching, or time marching alone, until settled, when Newton is off or fails.

#include <functional>
#include <string>

#include "scenarios/run_cost.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::scenarios {

// How the run started, for the recording and the progress line.
struct InitialState {
  std::string description;       // for the recording's metadata
  double progress_weight = 0.0;  // share of the run's progress spent settling
};

// Brings the canal to the steady state of its operating point at t = 0 and presets the
// reservoir PID so that the pump delivers the gate discharge. Newton first; then the experiment's
// settle_s of unrecorded marching (the command held at its operating point), or, when Newton is
// off or fails, the longer of that and options.settle_time. A failed Newton is an error when
// options.require_steady_state, else a warning. `report` takes the run's progress fraction.
InitialState settle(BuiltCanal& canal, const Scenario& scenario, const ExperimentSpec& experiment,
                    const SimulateOptions& options, const std::function<void(double)>& report, RunCostGuard& guard);

// A warning of the run through the caller's channel (options.warning), else on stderr.
void warn(const SimulateOptions& options, const std::string& message);

}  // namespace canalsim::scenarios
