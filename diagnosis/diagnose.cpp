#include "diagnosis/diagnose.hpp"

#include "core/laws.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <mutex>
#include <thread>

#include "reduced_models/metrics.hpp"
#include "calibration/replay.hpp"
#include "core/parallel.hpp"

namespace canalsim::diagnosis {
namespace {

using scenarios::Scenario;

using calibration::Channels;
using calibration::is_level;
using calibration::observe;
using Prepared = calibration::Replay;

std::string format(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// The replay settings of the diagnosis options (calibration/replay.hpp).
calibration::ReplayOptions replay_options(const DiagnoseOptions& o) {
  calibration::ReplayOptions r;
  r.channels = o.channels;
  r.fit_fraction = o.fit_fraction;
  r.use_recorded_upstream = o.use_recorded_upstream;
  r.command_lead_samples = o.command_lead_samples;
  r.reconstruct_clock = o.reconstruct_clock;
  r.settle_time_s = o.settle_time_s;
  r.warmup_s = o.warmup_s;
  return r;
}

// Gate position under a constant-speed actuator (paper eq. 16) driven by the replayed command
// (the drive's t_s/u_mm step function, exactly as the simulation replays it), at `samples`.
std::vector<double> rate_limited_position(const Recording& drive, const std::vector<double>& samples, double speed_mm_s) {
  const auto& ct = drive.column(columns::time);
  const auto& cu = drive.column(columns::gate_command);
  // An infinite speed (or inf * 0) is the ideal actuator: at the command (laws::rate_limited_move).
  const auto move = laws::rate_limited_move;
  std::vector<double> x;
  x.reserve(samples.size());
  double pos = cu.front(), now = ct.front();
  std::size_t j = 0;
  for (double s : samples) {
    while (j + 1 < ct.size() && ct[j + 1] <= s) {
      pos = move(pos, cu[j], speed_mm_s * (ct[j + 1] - now));
      now = ct[j + 1];
      ++j;
    }
    pos = move(pos, cu[j], speed_mm_s * (s - now));
    now = s;
    x.push_back(pos);
  }
  return x;
}

// Evaluated hypothesis: its parameter, predictions and weighted fitted-part residual vector.
struct Point {
  double theta = 0.0;
  std::vector<Channels> prediction;
  std::vector<double> r;   // sqrt(w_c) (data - model) over the fitted parts, all channels
  double cost = 0.0;       // r·r / fitted samples
};

struct Costs {
  double fit = 0.0, heldout = 0.0;
  double nrmse_fit = 0.0, nrmse_heldout = 0.0;
  // Per-channel mean squared residual (raw units²) on the fitted and held-out parts.
  std::map<std::string, double> mse_fit, mse_heldout;
};

class Engine {
 public:
  Engine(const Scenario& base, const DiagnoseOptions& options) : base_(base), o_(options) {}

  void prepare(const std::vector<Recording>& recordings);
  void simulate_nominal();
  EffectResult evaluate_candidate(Effect effect);
  Point evaluate(Effect effect, double theta);
  Costs costs(const std::vector<Channels>& prediction) const;
  // Channel-balanced cost: the mean over channels of MSE_c / MSE_c(nominal), each nominal MSE
  // floored at a sensor-noise level, so an effect that explains one channel's residual counts
  // however small that channel's share of the weighted cost (a 0.1 mm lattice error in the
  // levels next to gate-position glitches).
  double balanced(const Costs& c, bool heldout) const;

  const std::vector<Prepared>& recordings() const { return recs_; }
  const std::vector<Channels>& nominal() const { return nominal_; }
  const std::map<std::string, double>& scale() const { return scale_; }
  double period() const { return period_; }
  double base_resolution() const { return sensors_.resolution_mm; }
  const Point* best_point(const std::string& name) const {
    const auto it = best_.find(name);
    return it == best_.end() ? nullptr : &it->second;
  }
  std::function<void(const std::string&)> on_simulation;

 private:
  Channels simulate_true(const Scenario& s, const Prepared& p);
  std::vector<Channels> predict(Effect effect, double theta);
  std::vector<double> fit_residuals(const std::vector<Channels>& prediction) const;
  Point secant_fit(Effect effect, const Point& start, int& sims);
  Point rate_limit_from_position(int& sims);
  double lattice_resolution() const;
  double reading_spread(double resolution) const;
  double heldout_coherence(double r) const;
  double correlation_inflation() const { return inflation_; }

  const Scenario& base_;
  const DiagnoseOptions& o_;
  std::vector<Prepared> recs_;
  SensorModel sensors_;
  double period_ = 0.13;
  std::map<std::string, double> scale_, weight_;
  std::vector<Channels> truth_;      // nominal, ideal sensors
  std::vector<Channels> nominal_;    // nominal, scenario sensors
  std::vector<double> inflow_m3s_;
  Point nominal_point_;
  Costs nominal_costs_;
  double inflation_ = 1.0;           // N / N_eff of the nominal primary residual
  std::size_t fit_samples_ = 0;
  std::map<std::string, Point> best_;
};

void Engine::prepare(const std::vector<Recording>& recordings) {
  sensors_ = sensor_model_of(base_.sensors);
  period_ = base_.sensors.period_s;
  const calibration::ReplayOptions replay = replay_options(o_);
  for (const Recording& rec : recordings) recs_.push_back(calibration::prepare_replay(rec, base_, replay));
  calibration::ChannelWeights w = calibration::channel_weights(recs_, o_.channels);
  scale_ = std::move(w.scale);
  weight_ = std::move(w.weight);
  for (const auto& p : recs_) fit_samples_ += p.data.size() * p.n_fit;
}

Channels Engine::simulate_true(const Scenario& s, const Prepared& p) {
  Channels out = calibration::replay_true(s, p, replay_options(o_));
  if (on_simulation) on_simulation(p.name);
  return out;
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
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) { truth_[i] = simulate_true(base_, recs_[i]); });
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

std::vector<Channels> Engine::predict(Effect effect, double theta) {
  const double parameter = to_parameter(effect, theta);
  std::vector<Channels> out(recs_.size());
  if (info(effect).sensor_only) {
    SensorModel m = sensors_;
    apply_effect(effect, parameter, m);
    if (effect == Effect::sensor_quantization) {
      m.resolution_mm = std::max(parameter, sensors_.resolution_mm);
      m.reading_spread_mm = reading_spread(m.resolution_mm);
    }
    for (std::size_t i = 0; i < recs_.size(); ++i) out[i] = observe(truth_[i], m, period_);
    return out;
  }
  parallel_for(recs_.size(), o_.threads, [&](std::size_t i) {
    Scenario s = base_;
    apply_effect(effect, parameter, s, inflow_m3s_[i]);
    out[i] = observe(simulate_true(s, recs_[i]), sensors_, period_);
  });
  return out;
}

Point Engine::evaluate(Effect effect, double theta) {
  Point p;
  p.theta = theta;
  p.prediction = predict(effect, theta);
  p.r = fit_residuals(p.prediction);
  p.cost = std::inner_product(p.r.begin(), p.r.end(), p.r.begin(), 0.0) / static_cast<double>(std::max<std::size_t>(fit_samples_, 1));
  return p;
}

// Gauss–Newton with a secant Jacobian on the weighted residual vector: each step solves the
// one-parameter linearisation r(θ) ≈ r_best + J (θ − θ_best) between the best point and its
// nearest neighbour, within the catalog range.
Point Engine::secant_fit(Effect effect, const Point& start, int& sims) {
  const EffectInfo& e = info(effect);
  std::vector<Point> pts;
  pts.push_back(start);
  pts.push_back(evaluate(effect, std::clamp(e.theta_none + e.theta_probe, e.theta_low, e.theta_high)));
  ++sims;
  const double tol = 2e-3 * (e.theta_high - e.theta_low);
  while (sims < o_.max_evaluations) {
    const auto best = std::min_element(pts.begin(), pts.end(), [](const Point& a, const Point& b) { return a.cost < b.cost; });
    const Point* near = nullptr;
    for (const auto& q : pts) {
      if (&q == &*best) continue;
      if (!near || std::abs(q.theta - best->theta) < std::abs(near->theta - best->theta)) near = &q;
    }
    const double dtheta = best->theta - near->theta;
    if (dtheta == 0.0) break;
    double jj = 0.0, jr = 0.0;
    for (std::size_t k = 0; k < best->r.size(); ++k) {
      const double j = (best->r[k] - near->r[k]) / dtheta;
      jj += j * j;
      jr += j * best->r[k];
    }
    if (!(jj > 0.0)) break;
    // r = data - model, so the model's sensitivity is -J; the step minimises |r_best + J δ|².
    double step = -jr / jj;
    const double span = std::max(4.0 * std::abs(dtheta), 0.1 * (e.theta_high - e.theta_low));
    step = std::clamp(step, -span, span);
    const double next = std::clamp(best->theta + step, e.theta_low, e.theta_high);
    bool seen = false;
    for (const auto& q : pts) seen = seen || std::abs(q.theta - next) < tol;
    if (seen) break;
    pts.push_back(evaluate(effect, next));
    ++sims;
  }
  const auto best = std::min_element(pts.begin(), pts.end(), [](const Point& a, const Point& b) { return a.cost < b.cost; });
  return *best;
}

// The rate limit shows directly in the recorded gate position: fit the actuator speed to x_up
// against the command (golden section on θ = 1/v), then simulate once at the estimate.
Point Engine::rate_limit_from_position(int& sims) {
  std::vector<std::vector<double>> instants;
  for (const auto& p : recs_) {
    std::vector<double> at(p.n);
    for (std::size_t k = 0; k < p.n; ++k) at[k] = static_cast<double>(p.skip + k) * period_;
    instants.push_back(std::move(at));
  }
  auto cost = [&](double theta) {
    double s = 0.0;
    for (std::size_t i = 0; i < recs_.size(); ++i) {
      const Prepared& p = recs_[i];
      const auto& x = p.data.at(columns::gate_position);
      const std::vector<double> m =
          rate_limited_position(p.drive, instants[i], theta <= 0.0 ? std::numeric_limits<double>::infinity() : 1.0 / theta);
      for (std::size_t k = 0; k < p.n_fit; ++k) s += (x[k] - m[k]) * (x[k] - m[k]);
    }
    return s;
  };
  const EffectInfo& e = info(Effect::gate_rate_limit);
  // Coarse logarithmic scan in speed first: the cost has a plateau at high speed.
  double best_theta = 0.0, best_cost = cost(0.0);
  for (double v = 0.5; v <= 400.0; v *= 1.1) {
    const double c = cost(1.0 / v);
    if (c < best_cost) { best_cost = c; best_theta = 1.0 / v; }
  }
  if (best_theta > 0.0) {
    double a = best_theta / 1.1, b = std::min(best_theta * 1.1, e.theta_high);
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    for (int it = 0; it < 40; ++it) {
      const double c = b - g * (b - a), d = a + g * (b - a);
      if (cost(c) < cost(d)) {
        b = d;
      } else {
        a = c;
      }
    }
    best_theta = 0.5 * (a + b);
  }
  if (best_theta <= 0.0) return nominal_point_;
  ++sims;
  return evaluate(Effect::gate_rate_limit, best_theta);
}

// Least-squares lattice step: with k_i = nint(y_i / r), r = Σ y_i k_i / Σ k_i². Levels of tens of
// millimetres sit ~100 steps from zero, so the scan's 0.005 mm grid is refined to ~1e-5 mm; a
// step off by 1% would put the model's lattice a whole step away from the recorded one.
double refine_lattice(const std::vector<const std::vector<double>*>& series, double r) {
  for (int it = 0; it < 4; ++it) {
    double yk = 0.0, kk = 0.0;
    for (const auto* y : series) {
      for (double v : *y) {
        const double k = std::round(v / r);
        yk += v * k;
        kk += k * k;
      }
    }
    if (!(kk > 0.0)) break;
    r = yk / kk;
  }
  return r;
}

// The largest resolution r whose lattice r·k holds the recorded levels: |mean exp(2πi y/r)| near 1
// over a channel that spans at least six lattice steps. The scenario's resolution when none does.
double Engine::lattice_resolution() const {
  // Differences from each series' first sample: on the lattice when the samples are, and only
  // tens of steps from zero, so a coarse scan already finds the right multiples.
  std::vector<std::vector<double>> diffs;
  for (const auto& p : recs_) {
    for (const auto& [c, y] : p.data) {
      if (!is_level(c) || y.empty()) continue;
      std::vector<double> d(y.size());
      for (std::size_t k = 0; k < y.size(); ++k) d[k] = y[k] - y.front();
      diffs.push_back(std::move(d));
    }
  }
  std::vector<const std::vector<double>*> series;
  for (const auto& d : diffs) series.push_back(&d);
  for (double r = info(Effect::sensor_quantization).theta_high; r > sensors_.resolution_mm * 1.5; r -= 0.005) {
    double coherent = 0.0, total = 0.0;
    for (const auto* y : series) {
      const auto [lo, hi] = std::minmax_element(y->begin(), y->end());
      if (*hi - *lo < 6.0 * r) continue;
      std::complex<double> s = 0.0;
      for (double v : *y) s += std::polar(1.0, 2.0 * std::numbers::pi * v / r);
      coherent += std::abs(s);
      total += static_cast<double>(y->size());
    }
    if (total > 0.0 && coherent / total > 0.9) return refine_lattice(series, r);
  }
  return sensors_.resolution_mm;
}

// Lattice coherence |mean exp(2πi (y - y_first)/r)| of the held-out recorded levels.
double Engine::heldout_coherence(double r) const {
  std::complex<double> sum = 0.0;
  double count = 0.0;
  for (const auto& p : recs_) {
    for (const auto& [c, y] : p.data) {
      if (!is_level(c) || p.n_fit >= y.size()) continue;
      for (std::size_t k = p.n_fit; k < y.size(); ++k) sum += std::polar(1.0, 2.0 * std::numbers::pi * (y[k] - y[p.n_fit]) / r);
      count += static_cast<double>(y.size() - p.n_fit);
    }
  }
  return count > 0.0 ? std::abs(sum) / count : 0.0;
}

EffectResult Engine::evaluate_candidate(Effect effect) {
  const EffectInfo& e = info(effect);
  EffectResult out;
  out.name = e.name;
  out.parameter.name = e.parameter;
  out.parameter.unit = e.unit;
  const Costs& before = nominal_costs_;
  out.cost_before = balanced(before, false);
  out.heldout_cost_before = balanced(before, true);
  out.nrmse_before = out.nrmse_after = before.nrmse_fit;
  out.heldout_nrmse_before = out.heldout_nrmse_after = before.nrmse_heldout;
  out.cost_after = out.cost_before;
  out.heldout_cost_after = out.heldout_cost_before;
  if (const std::string why = unsupported_reason(effect, base_); !why.empty()) {
    out.note = why;
    out.parameter.value = no_effect_parameter(effect);
    return out;
  }
  int sims = 0;
  Point best;
  switch (effect) {
    case Effect::sensor_offset: {
      std::vector<double> d;
      for (std::size_t i = 0; i < recs_.size(); ++i) {
        for (const auto& [c, y] : recs_[i].data) {
          if (!is_level(c)) continue;
          for (std::size_t k = 0; k < recs_[i].n_fit; ++k) d.push_back(y[k] - nominal_[i].at(c)[k]);
        }
      }
      std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
      best = evaluate(effect, d.empty() ? 0.0 : d[d.size() / 2]);
      break;
    }
    case Effect::sensor_delay: {
      best = nominal_point_;
      best.theta = 0.0;
      for (double th = 0.02; th <= e.theta_high + 1e-9; th += 0.02) {
        Point p = evaluate(effect, th);
        if (p.cost < best.cost) best = std::move(p);
      }
      // Parabola through the grid neighbours.
      if (best.theta > 0.0 && best.theta < e.theta_high) {
        const double a = evaluate(effect, best.theta - 0.02).cost, c = evaluate(effect, best.theta + 0.02).cost;
        const double den = a - 2.0 * best.cost + c;
        if (den > 0.0) {
          Point p = evaluate(effect, best.theta + 0.01 * (a - c) / den);
          if (p.cost < best.cost) best = std::move(p);
        }
      }
      break;
    }
    case Effect::sensor_quantization: best = evaluate(effect, lattice_resolution()); break;
    case Effect::gate_rate_limit: {
      bool have_position = std::find(o_.channels.begin(), o_.channels.end(), columns::gate_position) != o_.channels.end();
      for (const auto& p : recs_) have_position = have_position && p.data.count(columns::gate_position) > 0;
      best = have_position ? rate_limit_from_position(sims) : secant_fit(effect, Point{0.0, nominal_, nominal_point_.r, nominal_point_.cost}, sims);
      if (std::isnan(best.theta)) best.theta = 0.0;
      break;
    }
    default: {
      Point start = nominal_point_;
      start.theta = e.theta_none;
      best = secant_fit(effect, start, sims);
    }
  }
  out.simulations = sims;
  double value = to_parameter(effect, best.theta);
  if (effect == Effect::sensor_quantization) value = std::max(value, sensors_.resolution_mm);
  out.parameter.value = value;
  const Costs after = costs(best.prediction);
  out.cost_after = balanced(after, false);
  out.heldout_cost_after = balanced(after, true);
  out.nrmse_after = after.nrmse_fit;
  out.heldout_nrmse_after = after.nrmse_heldout;
  out.score = out.heldout_cost_before > 0.0 ? (out.heldout_cost_before - out.heldout_cost_after) / out.heldout_cost_before : 0.0;
  const double n_eff = static_cast<double>(fit_samples_) / inflation_;
  out.delta_bic = n_eff * std::log(std::max(out.cost_after, 1e-300) / std::max(out.cost_before, 1e-300)) + std::log(n_eff);
  out.material = effect == Effect::sensor_quantization
                     ? value >= std::max(e.material, 2.0 * sensors_.resolution_mm)
                     : is_material(effect, value);
  // Uncertainty: curvature of the cost along θ from a small secant step (cheap effects), or
  // from the residual sensitivity between the estimate and the nominal (re-simulated ones),
  // inflated by the residual correlation.
  double jj = 0.0;
  const double d_theta = best.theta - (std::isnan(nominal_point_.theta) ? e.theta_none : nominal_point_.theta);
  if (std::abs(d_theta) > 0.0) {
    for (std::size_t k = 0; k < best.r.size(); ++k) {
      const double j = (best.r[k] - nominal_point_.r[k]) / d_theta;
      jj += j * j;
    }
  }
  if (jj > 0.0 && best.r.size() > 1) {
    const double sse = std::inner_product(best.r.begin(), best.r.end(), best.r.begin(), 0.0);
    const double theta_sd = std::sqrt(sse / static_cast<double>(best.r.size() - 1) / jj * inflation_);
    double slope = 1.0;
    if (effect == Effect::gate_rate_limit) slope = best.theta > 0.0 ? 1.0 / (best.theta * best.theta) : 0.0;
    if (effect == Effect::friction) slope = std::exp(best.theta);
    out.parameter.std = theta_sd * slope;
  }
  out.significant = out.material && out.score >= o_.min_score && -out.delta_bic >= o_.min_bic_gain;
  if (effect == Effect::sensor_quantization) {
    // A quantised reading is best predicted in the mean-square sense by the unquantised level, so
    // the squared-error cost cannot reward this effect. Its evidence is the lattice: the score is
    // the lattice coherence of the held-out levels at the step fitted on the first part.
    out.score = out.material ? heldout_coherence(value) : 0.0;
    out.significant = out.material && out.score >= 0.9;
  }
  best_[out.name] = std::move(best);
  return out;
}

std::vector<RecordingResiduals> residual_sets(const std::vector<Prepared>& recs, const std::vector<Channels>& model,
                                              const std::string& primary, double period) {
  std::vector<RecordingResiduals> out;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const Prepared& p = recs[i];
    RecordingResiduals r;
    r.name = p.name;
    r.operating_point_mm = p.operating_point_mm;
    r.period_s = period;
    r.t = p.t;
    r.u = p.u;
    r.level = p.data.at(primary);
    r.regime = p.regime;
    r.primary = primary;
    for (const auto& [c, y] : p.data) {
      const auto it = model[i].find(c);
      if (it == model[i].end()) continue;
      std::vector<double> e(p.n);
      for (std::size_t k = 0; k < p.n; ++k) e[k] = y[k] - it->second[k];
      r.residuals[c] = std::move(e);
    }
    r.nrmse_percent = reduced::nrmse_percent(model[i].at(primary), p.data.at(primary));
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<ResidualTests> tests_of(const std::vector<RecordingResiduals>& sets, const ResidualTestOptions& o) {
  std::vector<ResidualTests> out;
  for (const auto& r : sets) out.push_back(residual_tests(r.residuals.at(r.primary), r.u, o));
  return out;
}

}  // namespace

std::string DiagnoseOptions::validate() const {
  std::ostringstream out;
  if (!(fit_fraction > 0.1 && fit_fraction < 0.9)) out << "fit_fraction = " << fit_fraction << ": expected (0.1, 0.9)";
  else if (primary.empty()) out << "primary: expected a channel name";
  else if (std::find(channels.begin(), channels.end(), primary) == channels.end()) out << "channels: must include the primary channel " << primary;
  else if (!(min_score > 0.0 && min_score < 1.0)) out << "min_score = " << min_score << ": expected (0, 1)";
  else if (!(min_bic_gain >= 0.0)) out << "min_bic_gain = " << min_bic_gain << ": expected >= 0";
  else if (!(none_noise_factor > 0.0)) out << "none_noise_factor = " << none_noise_factor << ": expected > 0";
  else if (max_evaluations < 2 || max_evaluations > 50) out << "max_evaluations = " << max_evaluations << ": expected 2..50";
  else if (threads < 1) out << "threads = " << threads << ": expected >= 1";
  else if (!(command_lead_samples >= 0.0 && command_lead_samples <= 1.0)) out << "command_lead_samples = " << command_lead_samples << ": expected [0, 1]";
  else if (!(settle_time_s >= 0.0)) out << "settle_time_s = " << settle_time_s << ": expected >= 0";
  else if (!(warmup_s >= 0.0)) out << "warmup_s = " << warmup_s << ": expected >= 0";
  else if (const std::string t = tests.validate(); !t.empty()) out << "tests." << t;
  else if (const std::string l = locate.validate(); !l.empty()) out << "locate." << l;
  else {
    for (const auto& c : candidates) {
      if (!effect_from_name(c)) {
        out << "candidates: unknown effect '" << c << "' (expected one of " << catalog_names() << ")";
        break;
      }
    }
  }
  return out.str();
}

void set_noise_figures(const std::vector<RecordingResiduals>& sets, double resolution, Diagnosis& d) {
  double noise_sq = 0.0, rms_sq = 0.0, spread_sq = 0.0;
  std::size_t n = 0;
  for (const auto& r : sets) {
    const double sigma = noise_level(r.level, resolution);
    noise_sq += sigma * sigma;
    const auto& e = r.residuals.at(r.primary);
    rms_sq += std::inner_product(e.begin(), e.end(), e.begin(), 0.0);
    n += e.size();
    const double mean = std::accumulate(r.level.begin(), r.level.end(), 0.0) / static_cast<double>(r.level.size());
    double v = 0.0;
    for (double y : r.level) v += (y - mean) * (y - mean);
    spread_sq += v / static_cast<double>(r.level.size());
  }
  const auto count = static_cast<double>(std::max<std::size_t>(sets.size(), 1));
  d.noise = std::sqrt(noise_sq / count);
  d.nominal_rms = std::sqrt(rms_sq / static_cast<double>(std::max<std::size_t>(n, 1)));
  d.noise_limit_nrmse = 100.0 * (1.0 - d.noise / std::sqrt(std::max(spread_sq / count, 1e-300)));
}

bool set_verdict(Diagnosis& d, double none_noise_factor) {
  const bool within_noise = d.nominal_rms <= none_noise_factor * d.noise ||
                            std::all_of(d.tests_before.begin(), d.tests_before.end(),
                                        [](const ResidualTests& t) { return t.white() && t.uncorrelated(); });
  if (!d.effects.empty() && d.effects.front().significant) {
    const EffectResult& w = d.effects.front();
    d.verdict = w.name;
    d.reason = w.name == "sensor_quantization"
                   ? "the held-out levels lie on a " + format(w.parameter.value) + " mm lattice (coherence " +
                         format(std::round(100.0 * w.score) / 100.0) + ")"
                   : w.name + " reduces the held-out cost by " + format(std::round(100.0 * w.score)) + "% (" +
                         w.parameter.name + " = " + format(w.parameter.value) + " " + w.parameter.unit + ")";
    return true;
  }
  if (within_noise) {
    d.verdict = "none";
    d.reason = "the nominal residual (RMS " + format(d.nominal_rms) + " mm) is within the measurement noise (" +
               format(d.noise) + " mm) and no candidate improves the held-out fit";
  } else {
    d.verdict = "unexplained";
    d.reason = "the nominal residual (RMS " + format(d.nominal_rms) + " mm) exceeds " + format(none_noise_factor) +
               " x the noise (" + format(d.noise) + " mm) and no candidate improves the held-out fit significantly";
  }
  return false;
}

Diagnosis diagnose(const Scenario& scenario, const std::vector<Recording>& recordings, const DiagnoseOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) throw InputError("diagnose options: " + problem);
  const std::vector<std::string> problems = check_recordings(scenario, recordings);
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw InputError(all);
  }
  const auto started = std::chrono::steady_clock::now();
  Diagnosis d;
  std::vector<Effect> candidates;
  if (options.candidates.empty()) {
    for (const auto& e : catalog()) candidates.push_back(e.effect);
  } else {
    for (const auto& c : options.candidates) candidates.push_back(*effect_from_name(c));
  }
  Engine engine(scenario, options);
  // Progress: simulations counted against a rough budget (nominal + ~5 per re-simulated effect).
  std::size_t done = 0;
  std::string stage = "nominal";
  std::mutex progress_mutex;
  const double budget = static_cast<double>(recordings.size()) * (1.0 + 5.0 * static_cast<double>(candidates.size()));
  engine.on_simulation = [&](const std::string&) {
    if (!options.progress) return;
    const std::lock_guard lock(progress_mutex);
    ++done;
    options.progress({std::min(0.99, static_cast<double>(done) / budget), stage});
  };
  try {
    engine.prepare(recordings);
    if (!engine.recordings().empty() && !engine.recordings().front().data.count(options.primary)) {
      throw InputError(engine.recordings().front().name + ": missing the primary channel " + options.primary);
    }
    engine.simulate_nominal();
    const auto before_sets = residual_sets(engine.recordings(), engine.nominal(), options.primary, engine.period());
    d.mismatch = locate(before_sets, options.locate);
    d.tests_before = tests_of(before_sets, options.tests);
    d.channel_scale = engine.scale();
    set_noise_figures(before_sets, engine.base_resolution(), d);

    for (Effect effect : candidates) {
      stage = info(effect).name;
      d.effects.push_back(engine.evaluate_candidate(effect));
    }
    std::stable_sort(d.effects.begin(), d.effects.end(), [](const EffectResult& a, const EffectResult& b) {
      if (a.significant != b.significant) return a.significant;
      return a.score > b.score;
    });
    std::vector<Channels> corrected = engine.nominal();
    if (set_verdict(d, options.none_noise_factor)) corrected = engine.best_point(d.verdict)->prediction;
    const auto after_sets = residual_sets(engine.recordings(), corrected, options.primary, engine.period());
    d.mismatch_after = locate(after_sets, options.locate);
    d.tests_after = tests_of(after_sets, options.tests);
    for (std::size_t i = 0; i < engine.recordings().size(); ++i) {
      const Prepared& p = engine.recordings()[i];
      d.series.push_back(RecordingSeries{p.name, p.t, p.u, p.data.at(options.primary),
                                         engine.nominal()[i].at(options.primary), corrected[i].at(options.primary),
                                         p.n_fit});
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    d.ok = false;
    d.message = e.what();
  }
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (options.progress) options.progress({1.0, "done"});
  return d;
}

}  // namespace canalsim::diagnosis
