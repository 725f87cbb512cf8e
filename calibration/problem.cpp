#include "calibration/problem.hpp"

#include <cmath>
#include <numeric>

#include "core/parallel.hpp"

namespace canalsim::calibration {

using scenarios::Scenario;

ReplayProblem::ReplayProblem(const Scenario& base, std::vector<Parameter> parameters,
                             const std::vector<Recording>& recordings, const ReplayOptions& options, int threads,
                             const ChannelWeights* weights)
    : base_(base), parameters_(std::move(parameters)), options_(options), threads_(threads) {
  // In parallel: reconstructing a recording's command clock (command_switch_times) takes ~70 ms,
  // and a calibration builds a problem per grid and for its validation.
  replays_.resize(recordings.size());
  parallel_for(recordings.size(), threads_, [&](std::size_t i) {
    Replay r = prepare_replay(recordings[i], base, options_);
    // A replayed upstream level is an input, not a comparison.
    if (options_.use_recorded_upstream && recordings[i].has(columns::upstream_level)) r.data.erase(columns::upstream_level);
    replays_[i] = std::move(r);
  });
  weights_ = weights ? *weights : channel_weights(replays_, options_.channels);
  const bool upstream_replayed = options_.use_recorded_upstream &&
                                 std::any_of(recordings.begin(), recordings.end(),
                                             [](const Recording& r) { return r.has(columns::upstream_level); });
  for (const auto& p : parameters_) {
    // Offsets of the upstream sensor move the replayed upstream level, so they are hydraulic then.
    const bool moves_input = upstream_replayed && (p.name == "offset_mm" || p.name == "offset_y_up_mm");
    hydraulic_.push_back(!p.sensor_only || moves_input);
  }
  for (const auto& r : replays_) {
    first_row_.push_back(rows_);
    for (const auto& [c, y] : r.data) {
      if (weights_.weight.count(c)) rows_ += r.n_fit;
    }
  }
}

std::vector<double> ReplayProblem::start() const {
  std::vector<double> z;
  for (const auto& p : parameters_) z.push_back(p.to_search(p.get(base_)));
  return z;
}

Scenario ReplayProblem::scenario_at(const std::vector<double>& z) const {
  Scenario s = base_;
  for (std::size_t j = 0; j < parameters_.size(); ++j) parameters_[j].set(s, parameters_[j].from_search(z[j]));
  return s;
}

Channels ReplayProblem::simulate(const Scenario& s, std::size_t recording) {
  ++simulations_;
  return replay_true(s, replays_[recording], options_);
}

Channels ReplayProblem::observed(const Channels& truth, const Scenario& s) const {
  SensorModel m = sensor_model_of(s.sensors);
  m.resolution_mm = 0.0;  // unrounded: the mean-square-best prediction of a quantised reading
  return observe(truth, m, s.sensors.period_s);
}

bool ReplayProblem::same_hydraulics(const std::vector<double>& a, const std::vector<double>& b) const {
  if (a.size() != b.size()) return false;
  for (std::size_t j = 0; j < a.size(); ++j) {
    if (hydraulic_[j] && a[j] != b[j]) return false;
  }
  return true;
}

std::vector<Channels> ReplayProblem::truth_at(const std::vector<double>& z) {
  {
    const std::lock_guard lock(cache_mutex_);
    if (same_hydraulics(z, cached_z_)) return cached_truth_;
    if (same_hydraulics(z, jacobian_base_z_)) return jacobian_base_truth_;
  }
  const std::vector<Channels> truth = simulate_all(scenario_at(z));
  const std::lock_guard lock(cache_mutex_);
  cached_z_ = z;
  cached_truth_ = truth;
  return truth;
}

std::vector<Channels> ReplayProblem::predict(const std::vector<double>& z) { return observe_all(truth_at(z), scenario_at(z)); }

std::vector<Channels> ReplayProblem::predict(const Scenario& s) { return observe_all(simulate_all(s), s); }

std::vector<Channels> ReplayProblem::simulate_all(const Scenario& s) {
  std::vector<Channels> truth(replays_.size());
  parallel_for(replays_.size(), threads_, [&](std::size_t i) { truth[i] = simulate(s, i); });
  return truth;
}

std::vector<Channels> ReplayProblem::observe_all(const std::vector<Channels>& truth, const Scenario& s) const {
  std::vector<Channels> out;
  for (const auto& t : truth) out.push_back(observed(t, s));
  return out;
}

void ReplayProblem::prime_start(std::vector<Channels> truth) {
  if (truth.size() != replays_.size()) return;
  const std::lock_guard lock(cache_mutex_);
  cached_z_ = start();
  cached_truth_ = std::move(truth);
}

void ReplayProblem::residuals_of(std::size_t i, const Channels& prediction, double* out) const {
  const Replay& r = replays_[i];
  std::size_t row = 0;
  for (const auto& [c, y] : r.data) {
    const auto w = weights_.weight.find(c);
    if (w == weights_.weight.end()) continue;
    const double sw = std::sqrt(w->second);
    const auto m = prediction.find(c);
    for (std::size_t k = 0; k < r.n_fit; ++k) out[row++] = m == prediction.end() ? 0.0 : sw * (y[k] - m->second[k]);
  }
}

std::vector<double> ReplayProblem::residuals(const std::vector<Channels>& prediction) const {
  std::vector<double> r(rows_);
  for (std::size_t i = 0; i < replays_.size(); ++i) residuals_of(i, prediction[i], r.data() + first_row_[i]);
  return r;
}

std::vector<std::vector<double>> ReplayProblem::residual_series(const std::vector<Channels>& prediction) const {
  std::vector<std::vector<double>> out;
  for (std::size_t i = 0; i < replays_.size(); ++i) {
    for (const auto& [c, y] : replays_[i].data) {
      const auto m = prediction[i].find(c);
      if (m == prediction[i].end() || !weights_.weight.count(c)) continue;
      std::vector<double> e(replays_[i].n_fit);
      for (std::size_t k = 0; k < e.size(); ++k) e[k] = y[k] - m->second[k];
      out.push_back(std::move(e));
    }
  }
  return out;
}

std::vector<double> ReplayProblem::jacobian(const std::vector<double>& z, const std::vector<double>& r0) {
  // The statistics ask again for the Jacobian Levenberg–Marquardt took at its last point.
  if (z == cached_jacobian_z_ && (!cached_jacobian_secant_ || (secant_ && !refresh_))) return cached_jacobian_;
  const bool secant = secant_applies(z);
  refresh_ = false;
  std::vector<double> J(rows_ * parameters_.size(), 0.0);
  const std::vector<Channels> base_truth = truth_at(z);
  {
    // Kept apart from the last point: Levenberg–Marquardt's candidates that fail replace that,
    // and the statistics then ask again for the prediction where the Jacobian was taken.
    const std::lock_guard lock(cache_mutex_);
    jacobian_base_z_ = z;
    jacobian_base_truth_ = base_truth;
  }
  difference_columns(z, r0, base_truth, secant, J);
  if (secant) broyden_update(z, r0, J);
  cached_jacobian_z_ = z;
  cached_jacobian_r_ = r0;
  cached_jacobian_ = J;
  cached_jacobian_secant_ = secant;
  return J;
}

void ReplayProblem::difference_columns(const std::vector<double>& z, const std::vector<double>& r0,
                                       const std::vector<Channels>& base_truth, bool sensor_only, std::vector<double>& J) {
  const std::size_t p = parameters_.size(), n = replays_.size();
  std::vector<std::size_t> columns;
  for (std::size_t j = 0; j < p; ++j) {
    if (!sensor_only || !hydraulic_[j]) columns.push_back(j);
  }
  std::vector<double> steps(p);
  for (std::size_t j = 0; j < p; ++j) {
    const Parameter& q = parameters_[j];
    double h = q.step;
    // Step inwards at the upper bound.
    if (z[j] + h > q.to_search(q.high)) h = -h;
    steps[j] = h;
  }
  // Every (parameter, recording) pair is one task: a simulation for hydraulic parameters, a
  // re-observation of the base simulation for sensor-only ones.
  parallel_for(columns.size() * n, threads_, [&](std::size_t task) {
    const std::size_t j = columns[task / n], i = task % n;
    std::vector<double> zj = z;
    zj[j] += steps[j];
    const Scenario s = scenario_at(zj);
    const Channels prediction = observed(hydraulic_[j] ? simulate(s, i) : base_truth[i], s);
    const std::size_t first = first_row_[i];
    const std::size_t last = i + 1 < n ? first_row_[i + 1] : rows_;
    std::vector<double> r(last - first);
    residuals_of(i, prediction, r.data());
    for (std::size_t k = 0; k < r.size(); ++k) J[(first + k) * p + j] = (r[k] - r0[first + k]) / steps[j];
  });
}

bool ReplayProblem::secant_applies(const std::vector<double>& z) const {
  if (!secant_ || refresh_ || cached_jacobian_z_.size() != z.size() || cached_jacobian_r_.size() != rows_) return false;
  for (std::size_t j = 0; j < z.size(); ++j) {
    if (hydraulic_[j] && z[j] != cached_jacobian_z_[j]) return true;
  }
  return false;
}

void ReplayProblem::broyden_update(const std::vector<double>& z, const std::vector<double>& r0, std::vector<double>& J) const {
  const std::size_t p = parameters_.size();
  std::vector<double> dz(p);
  double hydraulic_step_squared = 0.0;
  for (std::size_t j = 0; j < p; ++j) {
    dz[j] = z[j] - cached_jacobian_z_[j];
    if (hydraulic_[j]) hydraulic_step_squared += dz[j] * dz[j];
  }
  for (std::size_t k = 0; k < rows_; ++k) {
    const double* last = &cached_jacobian_[k * p];
    double* row = &J[k * p];
    // What the last Jacobian (its hydraulic columns; the sensor-only ones as differenced now)
    // did not predict of the residuals' change over the step.
    double unexplained = r0[k] - cached_jacobian_r_[k];
    for (std::size_t j = 0; j < p; ++j) unexplained -= (hydraulic_[j] ? last[j] : row[j]) * dz[j];
    for (std::size_t j = 0; j < p; ++j) {
      if (hydraulic_[j]) row[j] = last[j] + unexplained * dz[j] / hydraulic_step_squared;
    }
  }
}

double cost_per_sample(const std::vector<double>& residuals) {
  return residuals.empty() ? 0.0
                           : std::inner_product(residuals.begin(), residuals.end(), residuals.begin(), 0.0) /
                                 static_cast<double>(residuals.size());
}

}  // namespace canalsim::calibration
