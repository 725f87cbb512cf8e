// Identification of the reduced models (paper Sections 5–7): minimise IAE (eq. 20) — or IAE_c
// (eq. 21) for a nominal model over several recordings — under bounds with NLopt's
// derivative-free bounded optimisers.
//
// Method (per fit):
//  1. Delay grid. The delay enters through a sampled shift, so the cost is flat in L between
//     samples and a gradient says nothing. The linear counterpart of the model (LIOM for the
//     integer models, SOPD for SOPD, LFOM for the fractional ones) is simulated once per start
//     from a small grid of (T, λ); for every whole-sample shift inside the L bounds the gain is
//     set by least squares and the IAE computed (O(n) per shift). The best shift brackets L.
//  2. Refinement. NLopt (BOBYQA by default) minimises the IAE over all free parameters with L
//     continuous (fractional samples by linear interpolation) inside ±2 samples of the grid
//     optimum; the bracket is re-centred when L ends on its edge. For the linear models K is
//     profiled out exactly: for given (T, λ, L) the IAE-optimal gain is the weighted median of
//     y_i/g_i with weights |g_i| (g = unit-gain response), clipped to the K bounds.
//  3. Nonlinear models start from the linear fit (their head term is normalised by the mean
//     head, so K starts at the linear gain) and refine all their parameters.
// γ is fitted like any parameter unless fixed; gamma_sweep() instead fixes γ on a grid and picks
// the γ with the best Nrmse (eq. 19), as in the paper's Figures 8 and 10.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "reduced_models/data.hpp"
#include "reduced_models/metrics.hpp"
#include "reduced_models/models.hpp"

namespace canalsim::reduced {

// Bounds and starting value of one parameter. `fixed` holds it at `initial` (required then).
struct ParameterSpec {
  double lower = 0.0;
  double upper = 0.0;
  std::optional<double> initial;  // default: from the delay-grid stage / the linear fit
  bool fixed = false;
};

struct FitBounds {
  ParameterSpec K{-100.0, 100.0, std::nullopt, false};       // mm/mm
  ParameterSpec T{0.01, 60.0, std::nullopt, false};          // s
  ParameterSpec T2{0.0, 60.0, std::nullopt, false};          // s (SOPD)
  ParameterSpec lambda{0.1, 1.5, std::nullopt, false};       // fractional order
  ParameterSpec gamma{0.0, 10.0, std::nullopt, false};       // flow-law exponent (paper's search range)
  ParameterSpec L{0.0, 20.0, std::nullopt, false};           // delay, s
  ParameterSpec K_sub{-100.0, 100.0, std::nullopt, false};   // hybrid, mm/mm
  ParameterSpec gamma_sub{0.0, 10.0, std::nullopt, false};   // hybrid

  ParameterSpec& operator[](const std::string& name);
  const ParameterSpec& operator[](const std::string& name) const;
};

enum class Optimizer { bobyqa, sbplx, nelder_mead };

struct FitOptions {
  FitBounds bounds;
  // Actuator/sensor effects included in the fitted model (eqs. 16–17); not fitted.
  Actuation actuation;
  // GL memory used while fitting (paper: short memory, N = 500).
  SimulationOptions simulation;
  Optimizer optimizer = Optimizer::bobyqa;
  double relative_tolerance = 1e-4;  // NLopt xtol_rel and ftol_rel
  int max_evaluations = 2000;        // per NLopt run
  int restarts = 1;                  // NLopt reruns from the best point found
  int hybrid_restarts = 5;           // the same for the hybrid model (its cost is rougher)
  // Records longer than twice this are first fitted on their leading `coarse_samples` samples
  // (delay grid and search), then polished on the whole record; 0 = always the whole record.
  std::size_t coarse_samples = 2048;
  // Head references H of the nonlinear models (mm); 0 = mean head of the fitted data.
  double head_ref_mm = 0.0;
  double head_ref_sub_mm = 0.0;
  // Worker threads for fit_each() and gamma_sweep() (the machine has 2 cores).
  unsigned threads = 2;
  // Progress of fit_each() and gamma_sweep() (may be empty); called from one thread at a time.
  ProgressCallback progress;

  // Empty when valid; otherwise one line naming the field (e.g. "bounds.T: lower 5 > upper 1
  // excludes every model").
  std::string validate() const;
};

// Fit of one model to one or several recordings (several: a nominal model, IAE_c).
struct FitResult {
  Model model;
  std::vector<std::string> sources;
  std::vector<double> iae;                   // per recording (eq. 20), mm·s
  std::vector<double> nrmse;                 // per recording (eq. 19), %
  std::vector<std::vector<double>> response; // model output per recording, absolute mm
  double iae_total = 0.0;                    // Σ iae (IAE_c, eq. 21)
  int evaluations = 0;                       // cost evaluations spent
  int simulations = 0;                       // GL simulations spent (all recordings)
  bool converged = true;                     // false: an optimiser stopped on a limit/failure
  std::string message;                       // optimiser status, for reports
};

// Fits `kind` to one recording. Throws InputError naming the recording (missing y_up for a
// nonlinear model) or naming the bound that excludes every feasible model.
FitResult fit(ModelKind kind, const ExperimentData& data, const FitOptions& options = {});
// Nominal model: one parameter set minimising IAE_c over all recordings (eq. 21).
FitResult fit_nominal(ModelKind kind, const std::vector<ExperimentData>& data,
                      const FitOptions& options = {});
// Independent fits, one per recording, on `options.threads` threads.
std::vector<FitResult> fit_each(ModelKind kind, const std::vector<ExperimentData>& data,
                                const FitOptions& options = {});
// Continues a fit from a model's parameters (delay bracket around its L); used by the γ sweep.
FitResult refit_from(const Model& start, const std::vector<ExperimentData>& data,
                     const FitOptions& options);

struct GammaGrid {
  double first = 0.0, last = 10.0, step = 0.05;
  std::vector<double> values() const;
  std::string validate() const;
  // Parses "first:last:step" (e.g. "0:10:0.05"); throws InputError naming the text.
  static GammaGrid parse(const std::string& text);
};

struct GammaSweep {
  std::vector<double> gamma;
  std::vector<double> nrmse;  // mean Nrmse over the recordings at each γ, %
  std::vector<double> iae;    // IAE (IAE_c) at each γ
  std::size_t best = 0;       // index of the best Nrmse
  FitResult best_fit;         // the fit at gamma[best]
};

// For each γ on the grid, fits the model with γ fixed (a single recording, or a nominal model
// when several are given) and records Nrmse; picks the γ with the best Nrmse (Figs. 8, 10).
// Neighbouring γ warm-start each other; the grid is split across `options.threads` threads.
GammaSweep gamma_sweep(ModelKind kind, const std::vector<ExperimentData>& data,
                       const FitOptions& options, const GammaGrid& grid = {});

// Validation of a fitted model on another recording: IAE, Nrmse and the response.
struct Validation {
  std::string source;
  double iae = 0.0;
  double nrmse = 0.0;
  std::vector<double> response;
};
Validation validate_model(const Model& model, const ExperimentData& data,
                          const SimulationOptions& options = {});

// Weighted median: minimiser of Σ w_i |m − v_i| (w_i ≥ 0). Reorders its arguments.
double weighted_median(std::vector<double>& values, std::vector<double>& weights);

}  // namespace canalsim::reduced
