// One trial of the blind test (internal to diagnosis/): the recordings with the concealed effects,
// and the diagnosis of them — against the scenario, a reduced model, or (realistic) a calibration
// of the scenario on a clean baseline of another truth.
#pragma once

#include <vector>

#include "diagnosis/blindtest.hpp"

namespace canalsim::diagnosis::blind {

// What every trial shares.
struct TrialContext {
  const scenarios::Scenario& base;
  const std::vector<scenarios::ExperimentSpec>& experiments;
  const std::vector<double>& inflow_m3s;   // nominal inflow per experiment (lateral_outflow's reference)
  const BlindtestOptions& options;
  DiagnoseOptions diagnose;                // one thread: trials are the parallel unit
};

// Runs trial `trial.index` with its concealed effect(s) already drawn; fills the verdict and the
// scores. Throws on a failure (the caller records it).
void run_trial(const TrialContext& context, Trial& trial);

}  // namespace canalsim::diagnosis::blind
