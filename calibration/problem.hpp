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
  // Residual series per recording and compared channel (recording units), for statistics.
  std::vector<std::vector<double>> residual_series(const std::vector<Channels>& prediction) const;

 private:
  std::vector<Channels> truth_at(const std::vector<double>& z);
  Channels simulate(const scenarios::Scenario& s, std::size_t recording);
  Channels observed(const Channels& truth, const scenarios::Scenario& s) const;
  void residuals_of(std::size_t recording, const Channels& prediction, double* out) const;
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
};

}  // namespace canalsim::calibration
