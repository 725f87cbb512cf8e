// How the diagnosis tests record the laboratory's experiments: shortened, settled for less than
// the default 600 s (the same for the recordings and the model that diagnoses them), with level
// noise drawn from a seed of their own.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/recording.hpp"
#include "diagnosis/diagnose.hpp"
#include "scenarios/scenario.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::diagnosis {

inline constexpr double kSettle = 150.0;  // s of settling before every run, recorded or diagnosed

// Experiment `name` of `lab`, shortened to `duration_s`, read by `sensors` with Gaussian level
// noise of `noise_std_mm` drawn from `seed`.
inline scenarios::ExperimentSpec short_experiment(const scenarios::Scenario& lab, const std::string& name,
                                                  double duration_s, scenarios::SensorSpec sensors,
                                                  double noise_std_mm, std::uint64_t seed) {
  scenarios::ExperimentSpec e = *lab.find_experiment(name);
  e.duration_s = duration_s;
  sensors.noise_std_mm = noise_std_mm;
  sensors.seed = seed;
  e.sensors = sensors;
  return e;
}

// A run that settles for kSettle. `quiet` drops its warnings: a truth on the other limiter's
// finer grid (testing/realistic.hpp) falls back to time marching, which these tests expect.
inline scenarios::SimulateOptions settled_run(bool quiet = false) {
  scenarios::SimulateOptions so;
  so.settle_time = kSettle;
  if (quiet) so.warning = [](const std::string&) {};
  return so;
}

// The steady inflow of experiment `e` of `s` held at its operating opening [m³/s]: the reference
// of a concealed lateral_outflow, as the blind test takes it.
inline double steady_inflow_m3s(const scenarios::Scenario& s, scenarios::ExperimentSpec e) {
  e.input.kind = scenarios::InputKind::constant;
  e.duration_s = 2.0;
  return scenarios::simulate(s, e).column(columns::discharge).front() * 1e-3;
}

// A diagnosis among `candidates` whose model settles as the recordings did.
inline DiagnoseOptions among(const std::vector<std::string>& candidates) {
  DiagnoseOptions o;
  o.candidates = candidates;
  o.settle_time_s = kSettle;
  return o;
}

}  // namespace canalsim::diagnosis
