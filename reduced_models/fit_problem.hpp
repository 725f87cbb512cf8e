// Internals of the identification (identification.hpp), shared by its translation units:
//   fit_problem.cpp    the cost (IAE / IAE_c, K profiled out), the coarse scans and the NLopt
//                      refinement (stages 2–3);
//   delay_search.cpp   the delay search that starts every fit (stage 1);
//   identification.cpp the fit pipeline and the public entry points;
//   gamma_sweep.cpp    the γ grid and sweep.
// Not part of the module's interface.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "reduced_models/identification.hpp"

namespace canalsim::reduced::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Models whose output deviation is K times a response that does not depend on K (the forcing
// does not read the model's own output): K can be profiled out exactly.
bool output_linear_in_gain(ModelKind kind);
// The linear model whose delay search starts a fit of `kind` (LIOM, SOPD or LFOM).
ModelKind linear_counterpart(ModelKind kind);
std::vector<const ExperimentData*> pointers(const std::vector<ExperimentData>& data);
// Deviation of the recorded output from the operating point.
std::vector<double> output_deviation(const ExperimentData& d);

// One optimisation problem: a model kind, its data, which parameters NLopt moves, and whether
// K is profiled out (linear models).
class Problem {
 public:
  Problem(ModelKind kind, std::vector<const ExperimentData*> data, const FitOptions& options);

  const std::vector<std::string>& free_names() const { return free_; }
  Model& base() { return base_; }
  int evaluations() const { return evaluations_; }
  int simulations() const { return simulations_; }

  // Cost (IAE or IAE_c) of the model `m`; with K profiled, m.p.K is set to the optimal gain.
  double cost(Model& m);

  // Delay grid (stage 1) for a linear model: returns the start with the best whole-sample shift.
  Model delay_grid();

  // Coarse scans before the local refinement (the IAE is multimodal in γ, and for the hybrid in
  // the split of the gain between the regimes): alternately scans the exponents (γ, γ_sub) on a
  // small grid and, for the hybrid, the gains (K, K_sub) as multiples of the start, keeping the
  // best. About 30–60 cost evaluations.
  Model coarse_starts(const Model& start);

  // Stage 2: NLopt from `start` with L bracketed around start.p.L. Returns the best model.
  // `step_scale` scales NLopt's initial steps (1 = a fresh search, < 1 = polishing a good start);
  // `restarts` < 0 takes the count from the options.
  Model refine(const Model& start, double& best_cost, bool& converged, std::string& message,
               double step_scale = 1.0, int restarts = -1);

 private:
  Model run_nlopt(const Model& start, double L_lo, double L_hi, bool alternate, double& best_cost,
                  bool& converged, std::string& message);

  ModelKind kind_;
  std::vector<const ExperimentData*> data_;
  const FitOptions& options_;
  Model base_;
  std::vector<std::vector<double>> residual_;
  std::vector<std::string> free_;
  bool profile_K_ = false;
  int evaluations_ = 0;
  int simulations_ = 0;  // model simulations (one per recording per evaluation, fewer if cached)
  double step_scale_ = 1.0;
  struct CacheEntry {
    std::array<double, 3> key{};                  // (T, λ, T2)
    std::vector<std::vector<double>> responses;   // undelayed unit responses per recording
    unsigned long last_use = 0;
  };
  static constexpr std::size_t kCacheEntries = 4;
  std::vector<CacheEntry> cache_;
  unsigned long cache_clock_ = 0;
  std::vector<double> values_, weights_;
};

// Throws InputError when the recordings or the options cannot be fitted (no recording, invalid
// options, missing y_up, a delay bound as long as a recording).
void check_data_for_fit(ModelKind kind, const std::vector<const ExperimentData*>& data,
                        const FitOptions& options);
// The fit result of `model` on `data`: IAE, Nrmse and response per recording.
FitResult finish(const Model& model, const std::vector<const ExperimentData*>& data,
                 const SimulationOptions& simulation);
// Refinement from a model's parameters (delay bracket around its L), with the step scale and
// restart count of Problem::refine.
FitResult refit_impl(const Model& start, const std::vector<const ExperimentData*>& data,
                     const FitOptions& options, double step_scale, int restarts);

}  // namespace canalsim::reduced::detail
