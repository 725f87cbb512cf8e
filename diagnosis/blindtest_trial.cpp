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

// What simulates a realistic truth: the second simulator when it is chosen, else simulate().
scenarios::Simulator truth_simulator(const TrialContext& c) {
  const auto& realistic = c.options.realistic;
  if (realistic && realistic->scheme == TruthScheme::staggered) return scenarios::staggered_simulator(realistic->staggered);
  return {};
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
    Recording r = simulate_concealed(truth, e, concealed, c.inflow_m3s[k], so, truth_simulator(c));
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

bool outside_catalog(const std::string& effect) {
  const auto& names = outside_catalog_effects();
  return std::find(names.begin(), names.end(), effect) != names.end();
}

// The flow regime where a residual is largest ("" without a regime breakdown).
std::string regime_of(const Mismatch& m) {
  const GroupStat* top = nullptr;
  for (const auto& g : m.by_regime) {
    if (g.samples > 0 && (!top || g.rms > top->rms)) top = &g;
  }
  return top ? top->name : "";
}

// Where physics outside the catalog changes the truth's levels most: the level channel with the
// largest RMS change over the experiments (noise-free runs with and without it), and on that
// channel the flow regime (the truth's own) with the largest RMS change: "y_dw_mm, submerged";
// trial.signature_rms_mm is that channel's RMS change.
std::string truth_location(const TrialContext& c, const Scenario& truth, const ConcealedEffect& effect, const std::string& label,
                           Trial& trial) {
  const std::vector<Recording> with = record(c, truth, {effect}, {0.0, 1, 0, false, label});
  const std::vector<Recording> without = record(c, truth, {}, {0.0, 1, 0, false, label});
  std::map<std::string, std::pair<double, double>> channel_sq;  // name -> (sum of squares, samples)
  for (std::size_t i = 0; i < with.size(); ++i) {
    for (const char* name : {columns::upstream_level, columns::level_below_gate, columns::level_downstream_end}) {
      if (!with[i].has(name) || !without[i].has(name)) continue;
      const auto& a = with[i].column(name);
      const auto& b = without[i].column(name);
      auto& slot = channel_sq[name];
      for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) slot.first += (a[k] - b[k]) * (a[k] - b[k]);
      slot.second += static_cast<double>(std::min(a.size(), b.size()));
    }
  }
  if (channel_sq.empty()) return "";
  const auto top = std::max_element(channel_sq.begin(), channel_sq.end(),
                                    [](const auto& x, const auto& y) { return x.second.first < y.second.first; });
  const std::string channel = top->first;
  trial.signature_rms_mm = std::sqrt(top->second.first / std::max(top->second.second, 1.0));
  std::map<std::string, std::pair<double, double>> regime_sq;  // name -> (sum of squares, samples)
  for (std::size_t i = 0; i < with.size(); ++i) {
    if (!with[i].has(columns::regime)) continue;
    const auto& a = with[i].column(channel);
    const auto& b = without[i].column(channel);
    const auto& regime = with[i].column(columns::regime);
    for (std::size_t k = 0; k < std::min({a.size(), b.size(), regime.size()}); ++k) {
      auto& slot = regime_sq[std::lround(regime[k]) == static_cast<long>(RegimeCode::free) ? "free" : "submerged"];
      slot.first += (a[k] - b[k]) * (a[k] - b[k]);
      slot.second += 1.0;
    }
  }
  std::string regime;
  double largest = -1.0;
  for (const auto& [name, s] : regime_sq) {
    if (s.second > 0.0 && s.first / s.second > largest) {
      largest = s.first / s.second;
      regime = name;
    }
  }
  return channel + ", " + regime;
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
  if (outside_catalog(trial.truth.effect)) trial.truth_location = truth_location(c, truth, trial.truth, label + "/location", trial);

  trial.simulation_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  // The operator's workflow, the one `diagnose --baseline` runs (baseline.hpp).
  BaselineOptions options = r.baseline;
  options.diagnosis = c.diagnose;
  BaselineDiagnosis result = diagnose_with_baseline(c.base, baseline, recordings, options);
  trial.calibration_seconds = result.calibration.seconds;
  if (!trial.truth_location.empty()) {
    const auto errors = baseline_rms_by_channel(result.calibration);
    const auto on = errors.find(trial.truth_location.substr(0, trial.truth_location.find(',')));
    if (on != errors.end()) trial.model_error_mm = on->second;
  }
  return std::move(result.diagnosis);
}

Diagnosis diagnose_trial(const TrialContext& c, Trial& trial) {
  if (c.options.realistic) return diagnose_realistic(c, trial);
  const std::uint64_t seed = c.options.seed * 1000003ULL + static_cast<std::uint64_t>(trial.index) * 101ULL;
  const std::string label = "trial" + std::to_string(trial.index);
  const std::vector<Recording> recordings = record(c, c.base, concealed_of(trial), {c.options.noise_std_mm, seed, 0, false, label});
  if (outside_catalog(trial.truth.effect)) trial.truth_location = truth_location(c, c.base, trial.truth, label + "/location", trial);
  return c.options.model ? diagnose_model(recordings, *c.options.model) : diagnose(c.base, recordings, c.diagnose);
}

}  // namespace

void run_trial(const TrialContext& c, Trial& trial) {
  const Diagnosis d = diagnose_trial(c, trial);
  if (!d.ok) throw std::runtime_error(d.message);
  trial.verdict = d.verdict;
  trial.reason = d.reason;
  if (d.form) {
    trial.form = d.form->effect + (d.form->holds ? " holds:" : " does not hold:");
    for (const auto& e : d.form->estimates) {
      trial.form += " " + e.recording + " " + format_g(e.parameter.value, 4) + " ± " + format_g(e.departure_std, 2) +
                    " (model error " + format_g(e.model_error, 2) + ")";
    }
  }
  trial.named.clear();
  for (const auto& e : d.explanation) trial.named.push_back({e.name, e.parameter.value});
  // Realistic recordings hold no gate position: a twin of the concealed effect is as right.
  const bool gate_position = !c.options.realistic;
  trial.correct = names_effect(trial.verdict, trial.truth.effect, gate_position);
  // Physics outside the catalog: right when the unexplained residual is located where it acts.
  if (outside_catalog(trial.truth.effect)) {
    trial.located = d.unexplained ? d.unexplained->channel + ", " + regime_of(d.unexplained->where) : "";
    trial.correct = !trial.truth_location.empty() && trial.located == trial.truth_location;
    // What the calibrated model misses on clean recordings hides an effect smaller than it (the
    // acceptance rule of docs/diagnosis.md §6 for effects without a threshold of their own).
    if (!trial.correct && trial.verdict == "none" && !trial.second && trial.signature_rms_mm < trial.model_error_mm) {
      trial.correct = trial.below_model_error = true;
    }
  }
  // `none` on an effect the diagnosis says these recordings could not reveal is an honest answer.
  if (!trial.correct && trial.verdict == "none" && trial.truth.effect != "none" && !trial.second) {
    for (const auto& t : d.thresholds) {
      if (t.effect == trial.truth.effect && !t.reveals(trial.truth.value)) trial.correct = trial.below_threshold = true;
    }
  }
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
