#include "diagnosis/blindtest_trial.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "core/format.hpp"
#include "diagnosis/baseline.hpp"
#include "scenarios/simulate.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::diagnosis::blind {
namespace {

using scenarios::ExperimentSpec;
using scenarios::Scenario;

struct RecordingPlan {
  double noise_std_mm = 0.0;
  std::uint64_t sensor_seed = 1;      // experiment k uses sensor_seed + k
  std::uint64_t prbs_seed_offset = 0;
  bool levels_only = false;           // keep t, u and the levels (no gate position, no flow)
  std::string label;
};

// Realistic recordings hold what a laboratory logs: the command and the level sensors.
Recording levels_only(const Recording& r) {
  Recording out;
  for (const char* key : {"scenario", "experiment", "operating_opening_mm", "sampling_period_s"}) {
    if (const std::string v = r.meta(key); !v.empty()) out.set_meta(key, v);
  }
  out.source = r.source;
  for (const char* name : {columns::time, columns::gate_command, columns::upstream_level, columns::level_below_gate,
                           columns::level_downstream_end}) {
    if (r.has(name)) out.set_column(name, r.column(name));
  }
  return out;
}

// Every experiment simulated on `truth` with the concealed effects.
std::vector<Recording> record(const TrialContext& c, const Scenario& truth, const std::vector<ConcealedEffect>& concealed,
                              const RecordingPlan& plan) {
  std::vector<Recording> out;
  for (std::size_t k = 0; k < c.experiments.size(); ++k) {
    ExperimentSpec e = c.experiments[k];
    e.input.prbs_seed += plan.prbs_seed_offset;
    scenarios::SensorSpec sensors = e.sensors.value_or(truth.sensors);
    sensors.noise_std_mm = plan.noise_std_mm;
    sensors.seed = plan.sensor_seed + k;
    e.sensors = sensors;
    // The truth's own start: where its Newton steady state fails (minmod on the fine grid at the
    // free-flow points) it settles by time marching, which is as true a start; not the user's
    // concern, so not a warning.
    scenarios::SimulateOptions so;
    so.warning = [](const std::string&) {};
    Recording r = simulate_concealed(truth, e, concealed, c.inflow_m3s[k], so);
    r.source = plan.label + "/" + e.name;
    out.push_back(plan.levels_only ? levels_only(r) : std::move(r));
  }
  return out;
}

std::vector<ConcealedEffect> concealed_of(const Trial& t) {
  std::vector<ConcealedEffect> out;
  if (t.truth.effect != "none") out.push_back(t.truth);
  if (t.second) out.push_back(*t.second);
  return out;
}

// The realistic trial (blindtest.hpp): a perturbed truth simulated differently, a clean baseline
// of it calibrated on, the trial's recordings diagnosed against the calibrated scenario.
Diagnosis diagnose_realistic(const TrialContext& c, Trial& trial) {
  const RealisticTruth& r = *c.options.realistic;
  std::mt19937_64 rng(c.options.seed * 7919ULL + static_cast<std::uint64_t>(trial.index));
  const Scenario truth = scenarios::perturb_uncertain(scenarios::independent_truth(c.base, r.numerics), r.tolerances,
                                                      rng, &trial.truth_drawn);
  const double noise = std::uniform_real_distribution<double>(r.noise_low_mm, r.noise_high_mm)(rng);
  trial.truth_drawn += "; noise " + format_fixed(noise, 3) + " mm";
  const std::uint64_t seed = c.options.seed * 1000003ULL + static_cast<std::uint64_t>(trial.index) * 101ULL;
  const std::string label = "trial" + std::to_string(trial.index);
  const auto started = std::chrono::steady_clock::now();
  const std::vector<Recording> baseline =
      record(c, truth, {}, {noise, seed + 50, r.baseline_seed_offset, true, label + "/baseline"});
  const std::vector<Recording> recordings = record(c, truth, concealed_of(trial), {noise, seed, 0, true, label});

  trial.simulation_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  // The operator's workflow, the one `diagnose --baseline` runs (baseline.hpp).
  BaselineOptions options = r.baseline;
  options.diagnosis = c.diagnose;
  BaselineDiagnosis result = diagnose_with_baseline(c.base, baseline, recordings, options);
  trial.calibration_seconds = result.calibration.seconds;
  return std::move(result.diagnosis);
}

Diagnosis diagnose_trial(const TrialContext& c, Trial& trial) {
  if (c.options.realistic) return diagnose_realistic(c, trial);
  const std::uint64_t seed = c.options.seed * 1000003ULL + static_cast<std::uint64_t>(trial.index) * 101ULL;
  const std::vector<Recording> recordings =
      record(c, c.base, concealed_of(trial), {c.options.noise_std_mm, seed, 0, false, "trial" + std::to_string(trial.index)});
  return c.options.model ? diagnose_model(recordings, *c.options.model) : diagnose(c.base, recordings, c.diagnose);
}

}  // namespace

void run_trial(const TrialContext& c, Trial& trial) {
  const Diagnosis d = diagnose_trial(c, trial);
  if (!d.ok) throw std::runtime_error(d.message);
  trial.verdict = d.verdict;
  trial.named.clear();
  for (const auto& e : d.explanation) trial.named.push_back({e.name, e.parameter.value});
  // Realistic recordings hold no gate position: a twin of the concealed effect is as right.
  const bool gate_position = !c.options.realistic;
  trial.correct = names_effect(trial.verdict, trial.truth.effect, gate_position);
  const auto channel_of = [](const std::string& name) {
    const auto open = name.find('[');
    return open == std::string::npos ? std::string() : name.substr(open);
  };
  trial.channel_right = !channel_of(trial.truth.effect).empty() && channel_of(trial.verdict) == channel_of(trial.truth.effect);
  if (trial.second) {
    const auto named = [&](const std::string& e) {
      return std::any_of(trial.named.begin(), trial.named.end(),
                         [&](const EffectValue& n) { return names_effect(n.effect, e, gate_position); });
    };
    trial.both_named = named(trial.truth.effect) && named(trial.second->effect);
  }
  trial.parameter_error = std::numeric_limits<double>::quiet_NaN();
  for (const auto& e : d.effects) {
    if (e.name == trial.truth.effect) {
      trial.estimate = e.parameter.value;
      trial.parameter_error = parameter_error(trial.truth, e.parameter.value);
    }
    if (e.name == trial.verdict) trial.heldout_gain = e.heldout_nrmse_after - e.heldout_nrmse_before;
  }
}

}  // namespace canalsim::diagnosis::blind
