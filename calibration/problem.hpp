// The least-squares problem of a calibration: recordings replayed through a scenario edited by
// parameters, as a weighted residual vector of the search coordinates z, with its Jacobian by
// forward differences whose perturbed simulations run in parallel (core/parallel.hpp).
#pragma once

#include <atomic>
#include <mutex>
#include <string>
#include <vector>

#include "calibration/parameters.hpp"
#include "calibration/replay.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

class ReplayProblem {
 public:
  // `weights` of the channels: those of another problem (validation recordings are weighed like
  // the fitted ones), or null to derive them from these recordings.
  ReplayProblem(const scenarios::Scenario& base, std::vector<Parameter> parameters,
                const std::vector<Recording>& recordings, const ReplayOptions& options, int threads,
                const ChannelWeights* weights = nullptr);

  const std::vector<Parameter>& parameters() const { return parameters_; }
  const std::vector<Replay>& replays() const { return replays_; }
  const ChannelWeights& weights() const { return weights_; }
  std::size_t residual_count() const { return rows_; }
  int simulations() const { return simulations_; }

  std::vector<double> start() const;                                  // z of the scenario's values
  scenarios::Scenario scenario_at(const std::vector<double>& z) const;
  // What the sensors would read at z, per recording (unrounded levels). Throws what the
  // simulation throws (std::runtime_error naming time and cell). Simulates only where the
  // hydraulic parameters differ from both the last point asked and the last Jacobian's.
  std::vector<Channels> predict(const std::vector<double>& z);
  // The same for an edited scenario (the grid check): always simulated.
  std::vector<Channels> predict(const scenarios::Scenario& scenario);
  // Its simulations before the sensors (always simulated), and what its sensors read from them.
  std::vector<Channels> simulate_all(const scenarios::Scenario& scenario);
  std::vector<Channels> observe_all(const std::vector<Channels>& truth, const scenarios::Scenario& scenario) const;
  // Hands the problem simulate_all() of its own scenario, made by another problem on the same
  // recordings: predict(start()) then reuses them (a refined calibration starts where the coarser
  // one's grid check simulated).
  void prime_start(std::vector<Channels> truth);
  // sqrt(w_c) (recorded − predicted) over the fitted samples of every recording and channel.
  std::vector<double> residuals(const std::vector<Channels>& prediction) const;
  // Row-major residual_count() × parameters Jacobian of residuals() at z (r0 = residuals at z).
  std::vector<double> jacobian(const std::vector<double>& z, const std::vector<double>& r0);
  // Secant updates: while on, a Jacobian at a new point is the last one updated by the step
  // between them (Broyden 1965's rank-one update of the hydraulic columns; the sensor-only ones,
  // which cost no simulation, are differenced as always) — PEST's JACUPDATE, which saves the
  // simulations of a Jacobian per step where the Jacobian changes little from step to step. Off:
  // every Jacobian by differences, and one asked again at a point where a secant one was taken is
  // differenced. refresh_jacobian(): the next one by differences (after a step that failed).
  void use_secant_updates(bool on) { secant_ = on; }
  void refresh_jacobian() { refresh_ = true; }
  // Whether the last Jacobian was taken at z by differences (not a secant update).
  bool differenced_at(const std::vector<double>& z) const { return z == cached_jacobian_z_ && !cached_jacobian_secant_; }
  // Residual series per recording and compared channel (recording units), for statistics.
  std::vector<std::vector<double>> residual_series(const std::vector<Channels>& prediction) const;

 private:
  std::vector<Channels> truth_at(const std::vector<double>& z);
  Channels simulate(const scenarios::Scenario& s, std::size_t recording);
  Channels observed(const Channels& truth, const scenarios::Scenario& s) const;
  void residuals_of(std::size_t recording, const Channels& prediction, double* out) const;
  // Columns of J by forward differences: every parameter's, or only the sensor-only ones'.
  void difference_columns(const std::vector<double>& z, const std::vector<double>& r0,
                          const std::vector<Channels>& base_truth, bool sensor_only, std::vector<double>& J);
  // Whether jacobian(z) can update the last one: secant updates on, no refresh asked, a last
  // Jacobian of this size and a step of the hydraulic parameters since.
  bool secant_applies(const std::vector<double>& z) const;
  // J's hydraulic columns: the last Jacobian's, updated so that J (z − z_last) = r0 − r_last.
  void broyden_update(const std::vector<double>& z, const std::vector<double>& r0, std::vector<double>& J) const;
  bool same_hydraulics(const std::vector<double>& a, const std::vector<double>& b) const;

  const scenarios::Scenario& base_;
  std::vector<Parameter> parameters_;
  std::vector<bool> hydraulic_;     // changes the simulation (else re-observed only)
  ReplayOptions options_;
  int threads_;
  std::vector<Replay> replays_;
  ChannelWeights weights_;
  std::vector<std::size_t> first_row_;   // per recording
  std::size_t rows_ = 0;
  std::atomic<int> simulations_{0};
  std::mutex cache_mutex_;
  std::vector<double> cached_z_;
  std::vector<Channels> cached_truth_;
  std::vector<double> jacobian_base_z_;           // where the last Jacobian was taken
  std::vector<Channels> jacobian_base_truth_;
  std::vector<double> cached_jacobian_z_, cached_jacobian_;   // the last Jacobian (not thread-safe)
  std::vector<double> cached_jacobian_r_;                      // the residuals where it was taken
  bool cached_jacobian_secant_ = false;
  bool secant_ = false, refresh_ = false;
};

// The weighted cost per sample of residuals(): their mean square (1 when every channel misses by
// its noise).
double cost_per_sample(const std::vector<double>& residuals);

}  // namespace canalsim::calibration
