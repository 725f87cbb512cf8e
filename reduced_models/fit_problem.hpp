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
#include "reduced_models/sensor_reading.hpp"

namespace canalsim::reduced::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Models whose output deviation is K times a response that does not depend on K (the forcing
// does not read the model's own output): K can be profiled out exactly.
bool output_linear_in_gain(ModelKind kind);
// The linear model whose delay search starts a fit of `kind` (LIOM, SOPD or LFOM).
ModelKind linear_counterpart(ModelKind kind);
std::vector<const ExperimentData*> pointers(const std::vector<ExperimentData>& data);
// The parameter whose scale the delay trades off against and the delay search grids: "T", "Tz"
// for IDZ, nullptr for ID.
const char* dynamics_parameter(ModelKind kind);
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

  // Switches the cost to least squares, h Σ (y0_j + c_j + K g − y)², with K and one output
  // offset c_j per recording profiled out in closed form (models linear in K only).
  void use_least_squares();
  // The offsets c_j of the last least-squares evaluation.
  const std::vector<double>& offsets() const { return offsets_; }
  // Least squares on the sensor's mean reading y0 + c_j + K g + b(·) (sensor_reading.hpp)
  // instead of the level itself; K and c_j by three Gauss–Newton steps from the linear solution.
  void use_reading_bias(const ReadingBias& bias) { bias_ = bias; }

  // The unit-gain responses g_j of `m` (K = 1, no output quantiser; the deviation from each
  // recording's y0, delayed by m.p.L), one per recording.
  void unit_responses(const Model& m, std::vector<std::vector<double>>& g);

  // h Σ (reading − y)² of unit responses `g` (unit_responses) at m.p.K and the offsets of the
  // last least-squares evaluation: the sensor's mean reading if one is set, else the level.
  double squared_error(const Model& m, const std::vector<std::vector<double>>& g) const;

  // The least-squares polish (least_squares_polish.cpp): Levenberg–Marquardt from `start` on
  // the least-squares cost (with the sensor's mean reading if one is set), every free parameter
  // with L inside ±`bracket_s` of start.p.L, K and the output offsets moved with them. Returns
  // the optimum with K set (offsets() holds the offsets); `cost` as cost() gives it. `precise`:
  // stop at a relative cost change of 1e-12 (the answer), else of 1e-6 (a start for another
  // polish). Models linear in K whose output is not quantised (actuation.quantum_mm = 0) only.
  Model least_squares_polish(const Model& start, double bracket_s, bool precise, double& best_cost, bool& converged,
                             std::string& message);

  // Stage 1 for a linear model (delay_search.cpp): the cost profiled over every whole-sample
  // delay on a grid of dynamics; returns the best (K, T, λ, T2, L) as the start of refine().
  Model delay_search();

  // Coarse scans before the local refinement (the IAE is multimodal in γ, and for the hybrid in
  // the split of the gain between the regimes): alternately scans the exponents (γ, γ_sub) on a
  // small grid and, for the hybrid, the gains (K, K_sub) as multiples of the start, keeping the
  // best. About 30–60 cost evaluations.
  Model coarse_starts(const Model& start);

  // Stage 2: NLopt from `start` with L bracketed within ±`bracket_s` of start.p.L (0: two
  // samples; the bracket follows L when L ends on its edge). Returns the best model, never worse
  // than `start`. `step_scale` scales NLopt's initial steps (1 = a fresh search, < 1 = polishing
  // a good start); `restarts` < 0 takes the count from the options.
  Model refine(const Model& start, double& best_cost, bool& converged, std::string& message,
               double step_scale = 1.0, int restarts = -1, double bracket_s = 0.0);

 private:
  const std::vector<std::vector<double>>& undelayed_unit_responses(const Model& unit);
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
    std::array<double, 4> key{};                  // (T, λ, T2, Tz)
    std::vector<std::vector<double>> responses;   // undelayed unit responses per recording
    unsigned long last_use = 0;
  };
  static constexpr std::size_t kCacheEntries = 4;
  std::vector<CacheEntry> cache_;
  unsigned long cache_clock_ = 0;
  std::vector<double> values_, weights_;
  bool least_squares_ = false;
  std::vector<double> offsets_;
  ReadingBias bias_;
  // The least-squares cost of `m` with K and the offsets profiled: in closed form for the level,
  // then Gauss–Newton for the sensor's mean reading.
  double least_squares_cost(Model& m, const std::vector<std::vector<double>>& g);
  void linear_gain_and_offsets(Model& m, const std::vector<std::vector<double>>& g);
  void gauss_newton_gain_and_offsets(Model& m, const std::vector<std::vector<double>>& g);

};

// The scale of a parameter's finite-difference step: its magnitude, or a floor where it may be 0 —
// a sample period `h` for the times, 0.01 for the orders and exponents, 1e-3 for the gains.
double difference_scale(const std::string& name, double value, double h);

// Throws InputError when the recordings or the options cannot be fitted (no recording, invalid
// options, missing y_up, a delay bound as long as a recording).
void check_data_for_fit(ModelKind kind, const std::vector<const ExperimentData*>& data,
                        const FitOptions& options);
// The fit result of `model` on `data`: IAE, Nrmse and response per recording.
// With `offsets` (one per recording), the operating points are y0 + offset.
FitResult finish(const Model& model, const std::vector<const ExperimentData*>& data,
                 const SimulationOptions& simulation, const std::vector<double>& offsets = {});
// Fills r.parameter_names, r.std, r.correlation and r.inflation for the fit `r` of `data`
// (fit_statistics.cpp). `options`: the fit's options (a parameter fixed there, or with lower ==
// upper, is not fitted); `offsets_fitted`: the least-squares criterion estimated each recording's
// output offset (r.y0_mm), a nuisance parameter here; `bias`: the sensor's mean reading the
// polish fitted (nullptr or a zero step: the level itself).
void add_fit_statistics(FitResult& r, const std::vector<const ExperimentData*>& data, const FitOptions& options,
                        bool offsets_fitted, const ReadingBias* bias);
// Refinement from a model's parameters (delay bracket around its L), with the step scale and
// restart count of Problem::refine.
FitResult refit_impl(const Model& start, const std::vector<const ExperimentData*>& data,
                     const FitOptions& options, double step_scale, int restarts);

}  // namespace canalsim::reduced::detail
