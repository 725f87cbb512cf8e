#include "diagnosis/diagnose.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "calibration/calibrate.hpp"
#include "calibration/replay.hpp"
#include "core/declared_units.hpp"
#include "core/parallel.hpp"
#include "diagnosis/baseline.hpp"
#include "diagnosis/calibrated.hpp"
#include "diagnosis/scenario_engine.hpp"
#include "reduced_models/metrics.hpp"

namespace canalsim::diagnosis {
calibration::ReplayOptions diagnosis_replay(const DiagnoseOptions& o) {
  // A replay driven by the recorded upstream level starts where that level starts (as the
  // calibration's replay does): otherwise it would settle at the scenario's upstream level and
  // jump to the recorded one at the first sample. The scenario's own upstream model keeps its
  // level, so that a level-sensor offset stays a sensor effect.
  return {.channels = o.channels,
          .fit_fraction = o.fit_fraction,
          .use_recorded_upstream = o.use_recorded_upstream,
          .command_lead_samples = o.command_lead_samples,
          .reconstruct_clock = o.reconstruct_clock,
          .settle_time_s = o.settle_time_s,
          .warmup_s = o.warmup_s,
          .start_at_recorded_level = o.use_recorded_upstream,
          .warning = nullptr};
}

calibration::ReplayOptions calibration_replay_for_diagnosis() {
  calibration::ReplayOptions r = diagnosis_replay(DiagnoseOptions{});
  r.fit_fraction = 1.0;
  r.channels = calibration::CalibrateOptions::default_replay().channels;
  return r;
}

namespace scenario_engine {

using calibration::observe;

void Engine::prepare() {
  sensors_ = sensor_model_of(base_.sensors);
  period_ = base_.sensors.period_s;
  const calibration::ReplayOptions replay = diagnosis_replay(o_);
  for (const Recording& rec : recordings_) recs_.push_back(calibration::prepare_replay(rec, base_, replay));
  if (!recs_.empty() && !recs_.front().data.count(o_.primary)) {
    throw InputError(recs_.front().name + ": missing the primary channel " + o_.primary);
  }
  calibration::ChannelWeights w = calibration::channel_weights(recs_, o_.channels);
  scale_ = std::move(w.scale);
  weight_ = std::move(w.weight);
  for (const auto& p : recs_) fit_samples_ += p.data.size() * p.n_fit;
}

Scenario Engine::scenario_for(std::size_t i) const {
  Scenario s = base_;
  if (carried_lateral_ != 0.0) apply_effect(Effect::lateral_outflow, carried_lateral_, s, carried_inflow_m3s_.at(i));
  return s;
}

// The engine of the same recordings whose nominal model carries `effects`: hydraulic and sensor
// effects edit the scenario (catalog.hpp apply_effect); a lateral outflow keeps this engine's
// inflow as its reference, so that its fraction means the same in every engine.
std::unique_ptr<Engine> Engine::with_effects(const std::vector<std::pair<std::string, double>>& effects) const {
  auto engine = std::make_unique<Engine>(base_, recordings_, o_);
  engine->carried_lateral_ = carried_lateral_;
  engine->carried_inflow_m3s_ = carried_lateral_ != 0.0 ? carried_inflow_m3s_ : inflow_m3s_;
  for (const auto& [name, value] : effects) {
    const Effect effect = *effect_from_name(name);
    if (effect == Effect::lateral_outflow) {
      engine->carried_lateral_ += value;
    } else if (effect == Effect::sensor_quantization) {
      engine->base_.sensors.resolution_mm = std::max(value, base_.sensors.resolution_mm);
    } else {
      apply_effect(effect, value, engine->base_, 0.0);
    }
  }
  return engine;
}

Channels Engine::simulate_true(const Scenario& s, const Prepared& p) {
  return calibration::replay_true(s, p, diagnosis_replay(o_));
}

std::vector<double> Engine::fit_residuals(const std::vector<Channels>& prediction) const {
  std::vector<double> r;
  r.reserve(fit_samples_);
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    for (const auto& [c, y] : recs_[i].data) {
      const auto it = prediction[i].find(c);
      const double sw = std::sqrt(weight_.at(c));
      for (std::size_t k = 0; k < recs_[i].n_fit; ++k) {
        r.push_back(it == prediction[i].end() ? 0.0 : sw * (y[k] - it->second[k]));
      }
    }
  }
  return r;
}

Costs Engine::costs(const std::vector<Channels>& prediction) const {
  Costs c;
  double fit_n = 0.0, held_n = 0.0;
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    const Prepared& p = recs_[i];
    for (const auto& [name, y] : p.data) {
      const auto it = prediction[i].find(name);
      if (it == prediction[i].end()) continue;
      const double w = weight_.at(name);
      double sf = 0.0, sh = 0.0;
      for (std::size_t k = 0; k < p.n; ++k) {
        const double e = y[k] - it->second[k];
        (k < p.n_fit ? sf : sh) += e * e;
      }
      c.fit += w * sf;
      c.heldout += w * sh;
      c.mse_fit[name] += sf;
      c.mse_heldout[name] += sh;
      fit_n += static_cast<double>(p.n_fit);
      held_n += static_cast<double>(p.n - p.n_fit);
    }
    const auto& y = p.data.at(o_.primary);
    const auto& m = prediction[i].at(o_.primary);
    const auto split = static_cast<std::ptrdiff_t>(p.n_fit);
    c.nrmse_fit += reduced::nrmse_percent({m.begin(), m.begin() + split}, {y.begin(), y.begin() + split});
    c.nrmse_heldout += reduced::nrmse_percent({m.begin() + split, m.end()}, {y.begin() + split, y.end()});
  }
  c.fit /= std::max(fit_n, 1.0);
  c.heldout /= std::max(held_n, 1.0);
  for (auto& [name, v] : c.mse_fit) {
    double nf = 0.0, nh = 0.0;
    for (const auto& p : recs_) {
      if (p.data.count(name)) {
        nf += static_cast<double>(p.n_fit);
        nh += static_cast<double>(p.n - p.n_fit);
      }
    }
    v /= std::max(nf, 1.0);
    c.mse_heldout[name] /= std::max(nh, 1.0);
  }
  c.nrmse_fit /= static_cast<double>(std::max<std::size_t>(recs_.size(), 1));
  c.nrmse_heldout /= static_cast<double>(std::max<std::size_t>(recs_.size(), 1));
  return c;
}

double Engine::balanced(const Costs& c, bool heldout) const {
  const auto& mse = heldout ? c.mse_heldout : c.mse_fit;
  const auto& reference = heldout ? nominal_costs_.mse_heldout : nominal_costs_.mse_fit;
  double sum = 0.0;
  int count = 0;
  for (const auto& [name, v] : mse) {
    const double floor = name == columns::discharge ? 0.003 : 0.03;
    const auto it = reference.find(name);
    sum += v / std::max(it == reference.end() ? 0.0 : it->second, floor * floor);
    ++count;
  }
  return count ? sum / count : 0.0;
}

void Engine::simulate_nominal() {
  truth_.assign(recs_.size(), {});
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) { truth_[i] = simulate_true(scenario_for(i), recs_[i]); });
  nominal_.clear();
  inflow_m3s_.clear();
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    nominal_.push_back(observe(truth_[i], sensors_, period_));
    // The reference of lateral_outflow: the nominal mean inflow through the controlled gate.
    double q = 0.0;
    if (const auto it = truth_[i].find(columns::discharge); it != truth_[i].end()) {
      q = std::accumulate(it->second.begin(), it->second.end(), 0.0) / static_cast<double>(it->second.size()) * 1e-3;
    }
    inflow_m3s_.push_back(q);
  }
  nominal_costs_ = costs(nominal_);
  nominal_point_.theta = std::numeric_limits<double>::quiet_NaN();
  nominal_point_.prediction = nominal_;
  nominal_point_.r = fit_residuals(nominal_);
  nominal_point_.cost = std::inner_product(nominal_point_.r.begin(), nominal_point_.r.end(), nominal_point_.r.begin(), 0.0) /
                        static_cast<double>(std::max<std::size_t>(fit_samples_, 1));
  // Residual correlation: samples of a smooth residual are not independent.
  double n = 0.0, n_eff = 0.0;
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    std::vector<double> e(recs_[i].n_fit);
    for (std::size_t k = 0; k < e.size(); ++k) e[k] = recs_[i].data.at(o_.primary)[k] - nominal_[i].at(o_.primary)[k];
    n += static_cast<double>(e.size());
    n_eff += effective_samples(e);
  }
  inflation_ = std::max(1.0, n / std::max(n_eff, 1.0));
}

// σ of (true level − model level) for the expected reading of a sensor with resolution r: the
// nominal primary residual on the fitted part less the quantisation variance r²/12 it contains,
// at least a tenth of a step.
double Engine::reading_spread(double r) const {
  double sq = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    const auto& y = recs_[i].data.at(o_.primary);
    const auto& m = nominal_[i].at(o_.primary);
    for (std::size_t k = 0; k < recs_[i].n_fit; ++k) {
      sq += (y[k] - m[k]) * (y[k] - m[k]);
      ++n;
    }
  }
  const double mse = sq / static_cast<double>(std::max<std::size_t>(n, 1));
  return std::sqrt(std::max(mse - r * r / 12.0, 0.01 * r * r));
}

// What the sensors read with `effects` in the model: sensor effects re-observe the simulation of
// the hydraulic ones (the nominal one when there are none).
std::vector<Channels> Engine::predict(const std::vector<EffectAt>& effects, Readings readings) {
  SensorModel m = sensors_;
  std::vector<EffectAt> hydraulic;
  for (const auto& [effect, theta] : effects) {
    const double parameter = to_parameter(effect, theta);
    if (!info(effect).sensor_only) {
      hydraulic.push_back({effect, theta});
    } else if (effect == Effect::sensor_quantization) {
      m.resolution_mm = std::max(parameter, sensors_.resolution_mm);
      m.reading_spread_mm = reading_spread(m.resolution_mm);
    } else {
      apply_effect(effect, parameter, m);
    }
  }
  if (readings == Readings::expected && m.resolution_mm > 0.0 && m.reading_spread_mm == 0.0) {
    m.reading_spread_mm = reading_spread(m.resolution_mm);
  }
  const std::vector<Channels>& truth = hydraulic.empty() ? truth_ : simulated(hydraulic);
  std::vector<Channels> out(recs_.size());
  for (std::size_t i = 0; i < recs_.size(); ++i) out[i] = observe(truth[i], m, period_);
  return out;
}

// The recordings replayed with hydraulic effects, kept by their θ: a joint fit asks for the same
// hydraulics again (Levenberg–Marquardt's accepted point, then its Jacobian; a sensor effect's
// column). A bounded cache: it is emptied when full.
const std::vector<Channels>& Engine::simulated(const std::vector<EffectAt>& hydraulic) {
  std::vector<double> key;
  for (const auto& [effect, theta] : hydraulic) {
    key.push_back(static_cast<double>(effect));
    key.push_back(theta);
  }
  if (const auto it = simulations_.find(key); it != simulations_.end()) return it->second;
  constexpr std::size_t kKept = 24;
  if (simulations_.size() >= kKept) simulations_.clear();
  ++simulations_run_;
  std::vector<Channels> truth(recs_.size());
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) {
    Scenario s = scenario_for(i);
    for (const auto& [effect, theta] : hydraulic) apply_effect(effect, to_parameter(effect, theta), s, inflow_m3s_[i]);
    truth[i] = simulate_true(s, recs_[i]);
  });
  return simulations_.emplace(std::move(key), std::move(truth)).first->second;
}

Point Engine::evaluate(const std::vector<EffectAt>& effects, Readings readings) {
  Point p;
  p.theta = effects.empty() ? std::numeric_limits<double>::quiet_NaN() : effects.back().theta;
  p.prediction = predict(effects, readings);
  p.r = fit_residuals(p.prediction);
  p.cost = std::inner_product(p.r.begin(), p.r.end(), p.r.begin(), 0.0) / static_cast<double>(std::max<std::size_t>(fit_samples_, 1));
  return p;
}

EffectResult Engine::explain(const std::string& candidate) {
  const Effect effect = *effect_from_name(candidate);
  if (const std::string why = unsupported_reason(effect, base_); !why.empty()) {
    EffectResult out = unchanged(effect, nominal_costs_);
    out.note = why;
    out.parameter.value = no_effect_parameter(effect);
    return out;
  }
  int sims = 0;
  switch (effect) {
    case Effect::sensor_offset: return judge(effect, fit_sensor_offset(), sims);
    case Effect::sensor_delay: return judge(effect, fit_sensor_delay(), sims);
    case Effect::sensor_quantization: return judge(effect, fit_sensor_quantization(), sims);
    case Effect::gate_rate_limit: {
      Point best = fit_gate_rate_limit(sims);
      return judge(effect, std::move(best), sims);
    }
    default: {
      Point start = nominal_point_;
      start.theta = info(effect).theta_none;
      Point best = fit_by_secant(effect, start, sims);
      return judge(effect, std::move(best), sims);
    }
  }
}

// Uncertainty of the parameter: the residual sensitivity between the estimate and the nominal
// point (a secant Jacobian), inflated by the residual correlation, mapped from θ to the
// parameter's unit.
double Engine::parameter_std(Effect effect, const Point& best) const {
  double jj = 0.0;
  const double d_theta = best.theta - (std::isnan(nominal_point_.theta) ? info(effect).theta_none : nominal_point_.theta);
  if (std::abs(d_theta) > 0.0) {
    for (std::size_t k = 0; k < best.r.size(); ++k) {
      const double j = (best.r[k] - nominal_point_.r[k]) / d_theta;
      jj += j * j;
    }
  }
  if (!(jj > 0.0) || best.r.size() <= 1) return 0.0;
  const double sse = std::inner_product(best.r.begin(), best.r.end(), best.r.begin(), 0.0);
  const double theta_sd = std::sqrt(sse / static_cast<double>(best.r.size() - 1) / jj * inflation_);
  return theta_sd * parameter_per_theta(effect, best.theta);
}

// Whether the effect moves the calibrated physics by more than calibrated_z standard deviations of
// what the baseline calibration left open (diagnosis/calibrated.hpp); true for an uncalibrated
// scenario.
bool Engine::beyond_calibration(Effect effect, double parameter) const {
  double opening = 0.0;
  for (const auto& p : recs_) opening += p.operating_point_mm / static_cast<double>(recs_.size());
  const double open = o_.calibrated_z * calibration_uncertainty(effect, base_, o_.calibrated_std, opening);
  return open == 0.0 || departure(effect, parameter) > open;
}

// An effect's result before it is fitted: its names, and the figures of `model` (the nominal
// one, or an explanation without the effect) before and after.
EffectResult Engine::unchanged(Effect effect, const Costs& model) const {
  const EffectInfo& e = info(effect);
  EffectResult out;
  out.name = e.name;
  out.parameter.name = e.parameter;
  out.parameter.unit = e.unit;
  out.cost_before = out.cost_after = balanced(model, false);
  out.heldout_cost_before = out.heldout_cost_after = balanced(model, true);
  out.nrmse_before = out.nrmse_after = model.nrmse_fit;
  out.heldout_nrmse_before = out.heldout_nrmse_after = model.nrmse_heldout;
  return out;
}

// Scores the model `with` the effect (at with.theta) against the model `without` it: costs before
// and after, held-out score, BIC, material and significance (pipeline.hpp's rule, with a held-out
// score of at least `min_score`). `within_calibration_counts`: the parameter must also exceed what
// the calibration leaves open (false where a jointly refitted effect spans that, calibrated.hpp).
EffectResult Engine::judged_against(Effect effect, const Point& with, const Costs& without, double min_score,
                                    bool within_calibration_counts) const {
  EffectResult out = unchanged(effect, without);
  const Costs after = costs(with.prediction);
  out.cost_after = balanced(after, false);
  out.heldout_cost_after = balanced(after, true);
  out.nrmse_after = after.nrmse_fit;
  out.heldout_nrmse_after = after.nrmse_heldout;
  out.score = out.heldout_cost_before > 0.0 ? (out.heldout_cost_before - out.heldout_cost_after) / out.heldout_cost_before : 0.0;
  const double n_eff = static_cast<double>(fit_samples_) / inflation_;
  out.delta_bic = bic_change(n_eff, out.cost_before, out.cost_after);
  out.parameter.value = to_parameter(effect, with.theta);
  out.material = is_material(effect, out.parameter.value) &&
                 (!within_calibration_counts || beyond_calibration(effect, out.parameter.value));
  // "Show the fit improve": the primary channel's held-out Nrmse must rise too, so that a pooled
  // cost cannot name an effect that fits the upstream channels while the levels downstream —
  // what the verdict is about — get worse (seen on calibrated realistic truths).
  out.significant = is_significant(out, {min_score, o_.min_bic_gain, true});
  return out;
}

// An effect at its fitted point, judged against the nominal model, with its uncertainty.
EffectResult Engine::judge(Effect effect, Point best, int sims) {
  const EffectInfo& e = info(effect);
  EffectResult out = judged_against(effect, best, nominal_costs_, o_.min_score, true);
  out.simulations = sims;
  out.parameter.std = parameter_std(effect, best);
  if (effect == Effect::sensor_quantization) {
    // A quantised reading is best predicted in the mean-square sense by the unquantised level, so
    // the squared-error cost cannot reward this effect. Its evidence is the lattice: a step at
    // least twice the modelled resolution, and the lattice coherence of the held-out levels at
    // the step fitted on the first part as the score.
    const double value = std::max(out.parameter.value, sensors_.resolution_mm);
    out.parameter.value = value;
    out.material = value >= std::max(e.material, 2.0 * sensors_.resolution_mm);
    out.score = out.material ? heldout_coherence(value) : 0.0;
    out.significant = out.material && out.score >= 0.9;
  }
  best_[out.name] = std::move(best);
  return out;
}

const std::vector<Channels>& Engine::prediction_with(const std::string& effect) const {
  return effect.empty() ? nominal_ : best_.at(effect).prediction;
}

std::vector<RecordingResiduals> Engine::nominal_residuals() {
  prepare();
  simulate_nominal();
  return residuals_with("");
}

std::vector<RecordingResiduals> Engine::residuals_with(const std::string& effect) const {
  const std::vector<Channels>& model = prediction_with(effect);
  std::vector<RecordingResiduals> out;
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    const Prepared& p = recs_[i];
    RecordingResiduals r;
    r.name = p.name;
    r.operating_point_mm = p.operating_point_mm;
    r.period_s = period_;
    r.t = p.t;
    r.u = p.u;
    r.level = p.data.at(o_.primary);
    r.regime = p.regime;
    r.primary = o_.primary;
    for (const auto& [c, y] : p.data) {
      const auto it = model[i].find(c);
      if (it == model[i].end()) continue;
      std::vector<double> e(p.n);
      for (std::size_t k = 0; k < p.n; ++k) e[k] = y[k] - it->second[k];
      r.residuals[c] = std::move(e);
    }
    r.nrmse_percent = reduced::nrmse_percent(model[i].at(o_.primary), p.data.at(o_.primary));
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<RecordingSeries> Engine::series_with(const std::string& effect) const {
  const std::vector<Channels>& corrected = prediction_with(effect);
  std::vector<RecordingSeries> out;
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    const Prepared& p = recs_[i];
    out.push_back(RecordingSeries{p.name, p.t, p.u, p.data.at(o_.primary), nominal_[i].at(o_.primary),
                                  corrected[i].at(o_.primary), p.n_fit});
  }
  return out;
}


}  // namespace scenario_engine


Status DiagnoseOptions::validate() const {
  Validator check;
  check.require(fit_fraction > 0.1 && fit_fraction < 0.9, "fit_fraction", fit_fraction, "(0.1, 0.9)");
  check.require(!primary.empty(), "primary", "expected a channel name");
  check.require(primary.empty() || std::find(channels.begin(), channels.end(), primary) != channels.end(),
                "channels", "must include the primary channel " + primary);
  check.require(min_score > 0.0 && min_score < 1.0, "min_score", min_score, "(0, 1)");
  check.require(added_min_score > 0.0 && added_min_score <= min_score, "added_min_score", added_min_score,
                "(0, min_score]");
  check.require(min_bic_gain >= 0.0, "min_bic_gain", min_bic_gain, ">= 0");
  check.require(none_noise_factor > 0.0, "none_noise_factor", none_noise_factor, "> 0");
  check.require(max_evaluations >= 2 && max_evaluations <= 50, "max_evaluations", max_evaluations, "2..50");
  check.require(threads >= 1, "threads", threads, ">= 1");
  check.require(command_lead_samples >= 0.0 && command_lead_samples <= 1.0, "command_lead_samples",
                command_lead_samples, "[0, 1]");
  check.require(settle_time_s >= 0.0, "settle_time_s", settle_time_s, ">= 0");
  check.require(warmup_s >= 0.0, "warmup_s", warmup_s, ">= 0");
  check.require(calibrated_z > 0.0, "calibrated_z", calibrated_z, "> 0");
  check.require(baseline_rms_mm >= 0.0, "baseline_rms_mm", baseline_rms_mm, ">= 0");
  check.require(baseline_factor > 0.0, "baseline_factor", baseline_factor, "> 0");
  for (const auto& [name, sd] : calibrated_std) {
    check.require(sd >= 0.0, "calibrated_std." + name, sd, ">= 0 (a standard deviation)");
  }
  check.nested("tests", tests.validate());
  check.nested("locate", locate.validate());
  for (const auto& c : candidates) {
    check.require(effect_from_name(c).has_value(), "candidates",
                  "unknown effect '" + c + "' (expected one of " + catalog_names() + ")");
  }
  return check.status();
}

Diagnosis diagnose(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings_as_recorded,
                   const DiagnoseOptions& given) {
  if (const Status status = given.validate(); !status) throw InputError("diagnose options: " + status.message());
  DiagnoseOptions options = given;
  if (options.calibrated_std.empty()) options.calibrated_std = calibrated_std_of(scenario);
  if (options.baseline_rms_mm == 0.0) options.baseline_rms_mm = scenario.calibrated_baseline_rms_mm;
  std::vector<Recording> recordings;
  for (const Recording& r : recordings_as_recorded) recordings.push_back(in_millimetres(r));
  const std::vector<std::string> problems = check_recordings(scenario, recordings);
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw InputError(all);
  }
  std::vector<std::string> candidates = options.candidates;
  if (candidates.empty()) {
    for (const auto& e : catalog()) candidates.emplace_back(e.name);
  }
  scenario_engine::Engine engine(scenario, recordings, options);
  PipelineSettings settings;
  settings.none_noise_factor = options.none_noise_factor;
  settings.tolerated_rms = options.baseline_factor * options.baseline_rms_mm;
  settings.tests = options.tests;
  settings.locate = options.locate;
  settings.progress = options.progress;
  return run_pipeline(engine, candidates, settings);
}

}  // namespace canalsim::diagnosis