#include "diagnosis/diagnose.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include "calibration/calibrate.hpp"
#include "calibration/replay.hpp"
#include "calibration/residual_breakdown.hpp"
#include "core/declared_units.hpp"
#include "core/format.hpp"
#include "core/parallel.hpp"
#include "diagnosis/baseline.hpp"
#include "diagnosis/calibrated.hpp"
#include "diagnosis/scenario_engine.hpp"
#include "reduced_models/metrics.hpp"
#include "scenarios/variation.hpp"

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

namespace {

// A replay that ends `lookahead` samples after the fitted part: the simulation stops there.
void end_after_fitted_part(Prepared& replay, std::size_t lookahead) {
  const std::size_t n = std::min(replay.n, replay.n_fit + lookahead);
  if (n == replay.n) return;
  replay.n = n;
  for (std::vector<double>* v : {&replay.t, &replay.u, &replay.regime}) {
    if (v->size() > n) v->resize(n);
  }
  for (auto& [channel, y] : replay.data) y.resize(n);
}

}  // namespace

void Engine::prepare() {
  sensors_ = sensor_model_of(base_.sensors);
  period_ = base_.sensors.period_s;
  const calibration::ReplayOptions replay = diagnosis_replay(o_);
  for (const Recording& rec : recordings_) recs_.push_back(calibration::prepare_replay(rec, base_, replay));
  if (!recs_.empty() && !recs_.front().data.count(o_.primary)) {
    throw InputError(recs_.front().name + ": missing the primary channel " + o_.primary);
  }
  for (const auto& c : o_.channels) {
    const bool everywhere = std::all_of(recs_.begin(), recs_.end(), [&](const Prepared& p) { return p.data.count(c) > 0; });
    if (calibration::is_level(c) && everywhere) level_channels_.push_back(c);
  }
  carry_command_and_reading_effects();
  calibration::ChannelWeights w = calibration::channel_weights(recs_, o_.channels);
  scale_ = std::move(w.scale);
  weight_ = std::move(w.weight);
  for (const auto& p : recs_) fit_samples_ += p.data.size() * p.n_fit;
  // A reading delay of either sign reads the level |delay| later; an explanation may carry one
  // and fit another, so a search replay runs twice the catalog's most negative delay, and a
  // second, past the fitted part.
  double ahead_s = 0.0;
  for (const EffectKind& kind : catalog()) {
    if (kind.search == Search::delay_grid) ahead_s = std::max(ahead_s, -kind.theta_low);
  }
  lookahead_ = static_cast<std::size_t>(std::ceil((2.0 * ahead_s + 1.0) / period_));
  // The search grid: halved while it has more than search_max_cells and every pool keeps cells
  // to halve.
  int fewest = std::numeric_limits<int>::max();
  for (const auto& pool : base_.pools) fewest = std::min(fewest, pool.cells);
  while (o_.search_max_cells > 0 && scenarios::total_cells(base_) > o_.search_max_cells * search_divisor_ &&
         fewest >= 8 * search_divisor_) {
    search_divisor_ *= 2;
  }
}

// The command effects an explanation carries edit the replays' drives; its reading effects the
// sensor model (a lattice on the phase the recorded levels sit at).
void Engine::carry_command_and_reading_effects() {
  for (const auto& [effect, value] : carried_) {
    if (effect.kind->acts == Acts::command) {
      for (auto& p : recs_) apply_effect(effect, value, p);
    } else if (effect.kind->acts == Acts::readings) {
      apply_effect(effect, value, sensors_);
      if (effect.kind->search == Search::lattice) {
        auto& fault = sensors_.channel_fault[effect.channel];
        fault.resolution_mm = std::max(value, sensors_.resolution_mm);
        fault.lattice_offset_mm = lattice_phase(effect.channel, fault.resolution_mm);
      }
    }
  }
}

// The scenario that replays recording i: the base with the carried hydraulic effects, a share of
// the inflow referred to the inflow of the engine that found it.
Scenario Engine::scenario_for(std::size_t i) const {
  Scenario s = base_;
  for (const auto& [effect, value] : carried_) {
    if (effect.kind->acts == Acts::hydraulics) apply_effect(effect, value, s, carried_inflow_m3s_.at(i));
  }
  return s;
}

// The engine of the same recordings whose nominal model carries `effects` (and this engine's):
// every effect keeps this engine's inflow as its reference, so that a share of it means the same
// in every engine.
std::unique_ptr<Engine> Engine::with_effects(const std::vector<std::pair<std::string, double>>& effects) const {
  auto engine = std::make_unique<Engine>(base_, recordings_, o_);
  engine->carried_ = carried_;
  engine->carried_inflow_m3s_ = carried_.empty() ? inflow_m3s_ : carried_inflow_m3s_;
  for (const auto& [name, value] : effects) engine->carried_.emplace_back(*effect_from_name(name), value);
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
      if (calibration::is_level(name)) {
        std::vector<double> heldout(p.n - p.n_fit);
        for (std::size_t k = p.n_fit; k < p.n; ++k) heldout[k - p.n_fit] = y[k] - it->second[k];
        for (double v : calibration::slower_than_fast_band(heldout, period_)) c.mse_heldout_slow[name] += v * v;
      }
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
    if (const auto slow = c.mse_heldout_slow.find(name); slow != c.mse_heldout_slow.end()) slow->second /= std::max(nh, 1.0);
  }
  c.nrmse_fit /= static_cast<double>(std::max<std::size_t>(recs_.size(), 1));
  c.nrmse_heldout /= static_cast<double>(std::max<std::size_t>(recs_.size(), 1));
  return c;
}

double cost_reference_floor(const std::string& channel) { return channel == columns::discharge ? 0.003 : 0.03; }

std::vector<Channels> moved_along(std::vector<Channels> prediction, const std::vector<SignatureMove>& moves) {
  for (std::size_t i = 0; i < prediction.size(); ++i) {
    for (auto& [channel, y] : prediction[i]) {
      for (const SignatureMove& m : moves) {
        const std::vector<double>& to = m.to.at(i).at(channel);
        const std::vector<double>& from = m.from.at(i).at(channel);
        for (std::size_t n = 0; n < y.size(); ++n) y[n] += m.per_unit * (to[n] - from[n]);
      }
    }
  }
  return prediction;
}

namespace {

// mean_c MSE_c / max(reference_c, floor_c²) over the channels of `mse`.
double balanced_over(const std::map<std::string, double>& mse, const std::map<std::string, double>& reference) {
  double sum = 0.0;
  int count = 0;
  for (const auto& [name, v] : mse) {
    const double floor = cost_reference_floor(name);
    const auto it = reference.find(name);
    sum += v / std::max(it == reference.end() ? 0.0 : it->second, floor * floor);
    ++count;
  }
  return count ? sum / count : 0.0;
}

}  // namespace

double Engine::balanced(const Costs& c, bool heldout) const {
  return heldout ? balanced_over(c.mse_heldout, nominal_costs_.mse_heldout) : balanced_over(c.mse_fit, nominal_costs_.mse_fit);
}

double Engine::balanced_slow(const Costs& c) const { return balanced_over(c.mse_heldout_slow, nominal_costs_.mse_heldout_slow); }

void Engine::simulate_nominal() {
  truth_.assign(recs_.size(), {});
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) { truth_[i] = simulate_true(scenario_for(i), recs_[i]); });
  observe_nominal();
}

void Engine::observe_nominal() {
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

// The sensor model with the reading effects among `effects`: a lattice on the phase the recorded
// levels sit at, read as its expectation given the model's spread.
SensorModel Engine::sensors_with(const std::vector<EffectAt>& effects, Readings readings) const {
  SensorModel m = sensors_;
  for (const auto& [effect, theta] : effects) {
    if (effect.kind->acts != Acts::readings) continue;
    const double parameter = to_parameter(effect, theta);
    if (effect.kind->search == Search::lattice) {
      auto& fault = m.channel_fault[effect.channel];
      fault.resolution_mm = std::max(parameter, sensors_.resolution_mm);
      fault.lattice_offset_mm = lattice_phase(effect.channel, fault.resolution_mm);
      m.reading_spread_mm = reading_spread(fault.resolution_mm);
    } else {
      apply_effect(effect, parameter, m);
    }
  }
  if (readings == Readings::expected && m.resolution_mm > 0.0 && m.reading_spread_mm == 0.0) {
    m.reading_spread_mm = reading_spread(m.resolution_mm);
  }
  return m;
}

// What the sensors read with `effects` in the model: reading effects re-observe the simulation of
// the hydraulic and command ones (the nominal one when there are none).
std::vector<Channels> Engine::predict(const std::vector<EffectAt>& effects, Readings readings) {
  std::vector<EffectAt> simulated_effects;
  for (const auto& e : effects) {
    if (e.effect.kind->acts != Acts::readings) simulated_effects.push_back(e);
  }
  const SensorModel m = sensors_with(effects, readings);
  const std::vector<Channels>& truth = simulated_effects.empty() ? truth_ : simulated(simulated_effects);
  std::vector<Channels> out(recs_.size());
  for (std::size_t i = 0; i < recs_.size(); ++i) out[i] = observe(truth[i], m, period_);
  return out;
}

// The recordings replayed with hydraulic effects, kept by their θ: a joint fit asks for the same
// hydraulics again (Levenberg–Marquardt's accepted point, then its Jacobian; a sensor effect's
// column). Replays on the search grid and those that end after the fitted part (ReplayScope) are
// kept apart from the scenario's whole ones.
const std::vector<Channels>& Engine::simulated(const std::vector<EffectAt>& hydraulic) {
  std::vector<std::pair<std::string, double>> effects;
  for (const auto& [effect, theta] : hydraulic) effects.emplace_back(effect.name(), theta);
  const bool search_grid = on_search_grid();
  const bool fitted_part_only = replays_ == Replays::search && o_.search_fitted_part_only;
  // A whole replay serves a search on the same grid too: the points a search compares are all of
  // one grid.
  if (const auto it = simulations_.find({effects, search_grid, false}); it != simulations_.end()) return it->second;
  SimulationKey key{std::move(effects), search_grid, fitted_part_only};
  if (const auto it = simulations_.find(key); it != simulations_.end()) return it->second;
  // Bounded: when full, the searches' partial replays go first (the whole ones serve the
  // detection thresholds' signatures and the joint fits' columns), then everything.
  constexpr std::size_t kKept = 48;
  if (simulations_.size() >= kKept) {
    std::erase_if(simulations_, [](const auto& entry) { return std::get<2>(entry.first); });
    if (simulations_.size() >= kKept) simulations_.clear();
  }
  if (search_grid && grid_correction_.empty()) correct_for_search_grid();
  ++simulations_run_;
  std::vector<Channels> truth(recs_.size());
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) {
    Scenario s = search_grid ? scenarios::with_cells_divided(scenario_for(i), search_divisor_) : scenario_for(i);
    Prepared replay = recs_[i];
    for (const auto& [effect, theta] : hydraulic) {
      if (effect.kind->acts == Acts::command) {
        apply_effect(effect, to_parameter(effect, theta), replay);
      } else {
        apply_effect(effect, to_parameter(effect, theta), s, inflow_m3s_[i]);
      }
    }
    if (fitted_part_only) end_after_fitted_part(replay, lookahead_);
    truth[i] = simulate_true(s, replay);
    if (search_grid) {
      for (auto& [channel, y] : truth[i]) {
        const std::vector<double>& correction = grid_correction_[i].at(channel);
        for (std::size_t k = 0; k < y.size(); ++k) y[k] += correction.at(k);
      }
    }
  });
  return simulations_.emplace(std::move(key), std::move(truth)).first->second;
}

void Engine::describe(Diagnosis& d) const {
  d.channel_scale = scale_;
  d.model_cells = scenarios::total_cells(base_);
  d.search_cells = scenarios::total_cells(scenarios::with_cells_divided(base_, search_divisor_));
}

// Defect correction between grids: a search replay on the coarse grid plus (nominal on the
// scenario's grid − nominal on the coarse grid) equals the scenario's grid exactly at the nominal
// point and, as a search moves away from it, is off only by how much the grid's own error changes
// with the effect — second order in the cell size and the effect together.
void Engine::correct_for_search_grid() {
  ++simulations_run_;
  grid_correction_.assign(recs_.size(), {});
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) {
    const Prepared& replay = recs_[i];
    const Channels coarse = simulate_true(scenarios::with_cells_divided(scenario_for(i), search_divisor_), replay);
    for (const auto& [channel, y] : coarse) {
      const std::vector<double>& fine = truth_.at(i).at(channel);
      std::vector<double>& correction = grid_correction_[i][channel];
      correction.resize(y.size());
      for (std::size_t k = 0; k < y.size(); ++k) correction[k] = fine.at(k) - y[k];
    }
  });
}

bool Engine::covers_heldout(const Point& p) const {
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    const auto it = p.prediction.at(i).find(o_.primary);
    if (it == p.prediction.at(i).end() || it->second.size() < recs_[i].n) return false;
  }
  return true;
}

Point Engine::replayed_whole(const std::vector<EffectAt>& effects, Point searched, Readings readings, int& sims) {
  if (covers_heldout(searched) && !searched.on_search_grid) return searched;
  ++sims;
  Point whole = evaluate(effects, readings);
  whole.theta = searched.theta;
  return whole;
}

Point Engine::evaluate(const std::vector<EffectAt>& effects, Readings readings) {
  Point p;
  p.theta = effects.empty() ? std::numeric_limits<double>::quiet_NaN() : effects.back().theta;
  p.prediction = predict(effects, readings);
  p.on_search_grid = on_search_grid() && std::any_of(effects.begin(), effects.end(), [](const EffectAt& e) {
                       return e.effect.kind->acts != Acts::readings;
                     });
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
  Point searched = fit(effect, sims);
  // A search stopped at its probe is judged there, on the search grid: its prospect showed that
  // it cannot reach significance. Should the judgement find it significant after all, its point
  // is replayed on the scenario's grid and judged again.
  if (stopped_at_probe_.count(effect.name())) {
    EffectResult at_probe = judge(effect, searched, sims);
    if (!at_probe.significant || !searched.on_search_grid) return at_probe;
  }
  Point best = replayed_whole({{effect, searched.theta}}, std::move(searched), Readings::as_sensor, sims);
  return judge(effect, std::move(best), sims);
}

std::vector<RecordingEstimate> Engine::per_recording_estimates(const std::string& name) {
  const Effect effect = *effect_from_name(name);
  if (recordings_.size() < 2 || effect.kind->acts == Acts::readings) return {};
  std::vector<std::vector<Recording>> alone;
  for (const Recording& r : recordings_) alone.push_back({r});
  std::vector<RecordingEstimate> out(recordings_.size());
  const bool fitted = unsupported_reason(effect, base_).empty();
  parallel_for(recordings_.size(), o_.threads, [&](std::size_t i) {
    ParameterEstimate parameter;
    parameter.name = effect.kind->parameter;
    parameter.unit = effect.kind->unit;
    if (!fitted) {  // the scenario cannot carry it: no estimate
      const double none = std::numeric_limits<double>::quiet_NaN();
      parameter.value = no_effect_parameter(effect);
      out[i] = {recs_.at(i).name, parameter, none, none, none};
      return;
    }
    // The engine of this recording alone. Its nominal replay is this engine's i-th, and an
    // estimate needs the fitted part only: no replay is judged on the held-out part.
    Engine engine(base_, alone[i], o_);
    engine.carried_ = carried_;
    engine.screen_searches_ = false;
    if (!carried_inflow_m3s_.empty()) engine.carried_inflow_m3s_ = {carried_inflow_m3s_.at(i)};
    engine.prepare();
    engine.truth_ = {truth_.at(i)};
    if (!grid_correction_.empty()) engine.grid_correction_ = {grid_correction_.at(i)};
    engine.observe_nominal();
    int sims = 0;
    const Point best = engine.fit(effect, sims);
    parameter.value = to_parameter(effect, best.theta);
    parameter.std = engine.parameter_std(effect, best);
    const double per_theta = parameter_per_theta(effect, best.theta);
    out[i] = {recs_.at(i).name, parameter, best.theta - effect.kind->theta_none,
              per_theta > 0.0 ? parameter.std / per_theta : std::numeric_limits<double>::quiet_NaN(),
              engine.model_error_theta(effect, best)};
  });
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
    if (r.regime.empty() && nominal_[i].count(columns::regime)) {
      r.regime = nominal_[i].at(columns::regime);
      for (double& code : r.regime) code = std::round(code);
    }
    r.fit_samples = p.n_fit;
    r.primary = o_.primary;
    for (const auto& [c, y] : p.data) {
      const auto it = model[i].find(c);
      if (it == model[i].end()) continue;
      std::vector<double> e(p.n);
      for (std::size_t k = 0; k < p.n; ++k) e[k] = y[k] - it->second[k];
      r.residuals[c] = std::move(e);
      if (calibration::is_level(c)) r.recorded[c] = y;
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
  check.require(search_max_cells >= 0, "search_max_cells", search_max_cells, ">= 0");
  check.require(command_lead_samples >= 0.0 && command_lead_samples <= 1.0, "command_lead_samples",
                command_lead_samples, "[0, 1]");
  check.require(settle_time_s >= 0.0, "settle_time_s", settle_time_s, ">= 0");
  check.require(warmup_s >= 0.0, "warmup_s", warmup_s, ">= 0");
  check.require(calibrated_z > 0.0, "calibrated_z", calibrated_z, "> 0");
  check.require(baseline_rms_mm >= 0.0, "baseline_rms_mm", baseline_rms_mm, ">= 0");
  for (const auto& [channel, rms] : baseline_rms_by_channel) {
    check.require(rms >= 0.0 && std::isfinite(rms), "baseline_rms_by_channel." + channel, rms, ">= 0");
  }
  for (const auto& [channel, rms] : baseline_slow_rms_by_channel) {
    check.require(rms >= 0.0 && std::isfinite(rms), "baseline_slow_rms_by_channel." + channel, rms, ">= 0");
  }
  check.require(baseline_factor > 0.0, "baseline_factor", baseline_factor, "> 0");
  for (const auto& [name, sd] : calibrated_std) {
    check.require(sd >= 0.0, "calibrated_std." + name, sd, ">= 0 (a standard deviation)");
  }
  check.nested("tests", tests.validate());
  check.nested("locate", locate.validate());
  for (const auto& c : candidates) {
    check.require(effect_from_name(c).has_value() || kind_named(c) != nullptr, "candidates",
                  "unknown effect '" + c + "' (expected one of " + catalog_names() + ")");
  }
  return check.status();
}

namespace {

// The compared level channels every recording carries.
std::vector<std::string> level_channels_of(const std::vector<Recording>& recordings, const std::vector<std::string>& channels) {
  std::vector<std::string> out;
  for (const auto& c : channels) {
    if (calibration::is_level(c) &&
        std::all_of(recordings.begin(), recordings.end(), [&](const Recording& r) { return r.has(c); })) {
      out.push_back(c);
    }
  }
  return out;
}

// The candidates to explain with: the catalog on these recordings' level channels, or the ones
// asked for (a per-channel kind without a channel stands for it on every level channel). A
// channel the recordings lack is an InputError.
std::vector<std::string> candidate_names(const std::vector<std::string>& asked, const std::vector<std::string>& levels,
                                         const std::vector<Recording>& recordings) {
  const std::vector<Effect> all = effects_for(levels);
  std::vector<std::string> out;
  if (asked.empty()) {
    for (const Effect& e : all) out.push_back(e.name());
    return out;
  }
  std::string compared;
  for (const auto& c : levels) compared += (compared.empty() ? "" : ", ") + c;
  for (const auto& name : asked) {
    if (const auto effect = effect_from_name(name)) {
      if (!effect->channel.empty() && std::find(levels.begin(), levels.end(), effect->channel) == levels.end()) {
        throw InputError("candidates: " + name + " names channel " + effect->channel + ", which " +
                         (recordings.empty() ? std::string("no recording") : recordings.front().source) +
                         " does not carry (level channels compared: " + compared + ")");
      }
      out.push_back(name);
      continue;
    }
    for (const Effect& e : all) {
      if (e.kind->name == name) out.push_back(e.name());
    }
  }
  return out;
}

}  // namespace

Diagnosis diagnose(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings_as_recorded,
                   const DiagnoseOptions& given) {
  if (const Status status = given.validate(); !status) throw InputError("diagnose options: " + status.message());
  DiagnoseOptions options = given;
  if (options.calibrated_std.empty()) options.calibrated_std = calibrated_std_of(scenario);
  if (options.baseline_rms_mm == 0.0) options.baseline_rms_mm = scenario.calibrated_baseline_rms_mm;
  if (options.baseline_rms_by_channel.empty()) options.baseline_rms_by_channel = scenario.calibrated_baseline_rms_by_channel;
  if (options.baseline_slow_rms_by_channel.empty()) {
    options.baseline_slow_rms_by_channel = scenario.calibrated_baseline_slow_rms_by_channel;
  }
  std::vector<Recording> recordings;
  for (const Recording& r : recordings_as_recorded) recordings.push_back(in_millimetres(r));
  const std::vector<std::string> problems = check_recordings(scenario, recordings);
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw InputError(all);
  }
  const std::vector<std::string> candidates =
      candidate_names(options.candidates, level_channels_of(recordings, options.channels), recordings);
  scenario_engine::Engine engine(scenario, recordings, options);
  PipelineSettings settings;
  settings.none_noise_factor = options.none_noise_factor;
  settings.significance = {options.min_score, options.min_bic_gain, true};
  settings.tolerated_rms = options.baseline_factor * options.baseline_rms_mm;
  for (const auto& [channel, rms] : options.baseline_rms_by_channel) {
    settings.tolerated_by_channel[channel] = options.baseline_factor * rms;
  }
  for (const auto& [channel, rms] : options.baseline_slow_rms_by_channel) {
    settings.tolerated_slow_by_channel[channel] = options.baseline_factor * rms;
  }
  settings.tests = options.tests;
  settings.locate = options.locate;
  settings.progress = options.progress;
  return run_pipeline(engine, candidates, settings);
}

}  // namespace canalsim::diagnosis