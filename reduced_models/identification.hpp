// Identification of the reduced models (paper Sections 5–7): minimise IAE (eq. 20) — or IAE_c
// (eq. 21) for a nominal model over several recordings — under bounds with NLopt's
// derivative-free bounded optimisers.
//
// Method (per fit; docs/reduced-models.md, "Identification"):
//  1. Delay search (delay_search.cpp). The cost of the linear counterpart (LIOM for the integer
//     models, SOPD, LFOM for the fractional ones, ID, IDZ) is profiled over every whole-sample
//     delay inside the L bounds for time constants on a grid spanning a quarter sample to three
//     record lengths (K by least squares at each delay; all delays at once by FFT correlation).
//  2. Refinement (fit_problem.cpp). NLopt (BOBYQA by default, restarts alternating with SBPLX)
//     minimises the IAE over all free parameters with L continuous (fractional samples by linear
//     interpolation) inside ±max(T/10, 2 samples) of the search's delay, re-centred when L ends on
//     its edge. For the models linear in K it is profiled out exactly: the IAE-optimal gain is the
//     weighted median of y_i/g_i with weights |g_i| (g = unit-gain response), clipped to its bounds.
//  3. Nonlinear models start from their linear counterpart's fit (their head term is normalised
//     by the mean head, so K starts at the linear gain) and refine all their parameters.
//  4. A model that contains another (LFOM ⊃ LIOM, NLIOM ⊃ LIOM, NLFOM ⊃ NLIOM and LFOM, IDZ ⊃ ID)
//     is also refined from that model's optimum and never fits worse than it.
//  Long records are searched on at most `search_samples` (block-averaged) samples, then polished.
// γ is fitted like any parameter unless fixed; gamma_sweep() instead fixes γ on a grid and picks
// the γ with the best Nrmse (eq. 19), as in the paper's Figures 8 and 10.
#pragma once

#include <limits>
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
  static constexpr double kFromData = std::numeric_limits<double>::infinity();

  ParameterSpec K{-100.0, 100.0, std::nullopt, false};       // mm/mm
  // Upper bounds of T, T2, Tz and L may be +∞: "from the data", ten times the longest recording
  // for T, T2 and Tz, half the shortest for L (the defaults). ID and IDZ have K in mm/(mm·s).
  ParameterSpec T{0.01, kFromData, std::nullopt, false};     // s
  ParameterSpec T2{0.0, kFromData, std::nullopt, false};     // s (SOPD)
  ParameterSpec lambda{0.1, 1.5, std::nullopt, false};       // fractional order
  ParameterSpec gamma{0.0, 10.0, std::nullopt, false};       // flow-law exponent (paper's search range)
  ParameterSpec L{0.0, kFromData, std::nullopt, false};      // delay, s
  ParameterSpec K_sub{-100.0, 100.0, std::nullopt, false};   // hybrid, mm/mm
  ParameterSpec gamma_sub{0.0, 10.0, std::nullopt, false};   // hybrid
  ParameterSpec Tz{0.0, kFromData, std::nullopt, false};     // IDZ zero, s

  ParameterSpec& operator[](const std::string& name);
  const ParameterSpec& operator[](const std::string& name) const;
};

enum class Optimizer { bobyqa, sbplx, nelder_mead };

// What a fit minimises.
//  iae            the paper's IAE (eq. 20; IAE_c, eq. 21, for a nominal model) throughout — the
//                 study's tables.
//  least_squares  the IAE fit, then a local least-squares polish of it on the recordings with
//                 the output offset of each recording estimated jointly (its operating point y0,
//                 which prepare_data takes from the samples before the first command change),
//                 K and the offsets in closed form, L continuous. Under Gaussian-like noise this
//                 is the (near-)efficient estimate: a slow pool's delay rests on the first
//                 millimetres of its rise, where an error of y0 is a delay error
//                 (docs/reduced-models.md, "Delay precision"). Applies to the models whose output
//                 is linear in K (LIOM, SOPD, LFOM, NLIOM-F, NLFOM-F, ID, IDZ); the others keep
//                 the IAE fit.
enum class Criterion { iae, least_squares };

struct FitOptions {
  FitBounds bounds;
  Criterion criterion = Criterion::iae;
  // Actuator/sensor effects included in the fitted model (eqs. 16–17); not fitted.
  Actuation actuation;
  // GL memory used while fitting (paper: short memory, N = 500).
  SimulationOptions simulation;
  Optimizer optimizer = Optimizer::bobyqa;
  double relative_tolerance = 1e-4;  // NLopt xtol_rel and ftol_rel
  int max_evaluations = 2000;        // per NLopt run
  // NLopt reruns from the best point found, alternating BOBYQA and SBPLX: the IAE of a quantised
  // output is rough, and one optimiser stalls where the other walks on. The nonlinear models
  // (NLIOM/NLFOM-S/F) need more: an NLIOM-F fit of a lab recording stopped at γ 2.73, IAE 8.9 mm·s,
  // after one restart and reached γ 3.01, IAE 5.4, after two; an NLFOM-F fit needed three.
  int restarts = 1;
  int nonlinear_restarts = 3;
  int hybrid_restarts = 5;           // the same for the hybrid model (its cost is rougher)
  // Records longer than this are searched (stages 1–3) on at most this many samples — block
  // averages as coarse as the input's fastest changes allow, from the start of the record — then
  // polished on the whole record; 0 = always search the whole record.
  std::size_t search_samples = 2048;
  // Head references H of the nonlinear models (mm); 0 = mean head of the fitted data.
  double head_ref_mm = 0.0;
  double head_ref_sub_mm = 0.0;
  // Worker threads for fit_each() and gamma_sweep() (the machine has 2 cores).
  unsigned threads = 2;
  // Progress of fit_each() and gamma_sweep() (may be empty); called from one thread at a time.
  ProgressCallback progress;

  // Ok, or one line naming the field (e.g. "bounds.T: lower 5 > upper 1 excludes every model").
  [[nodiscard]] Status validate() const;
};

// Fit of one model to one or several recordings (several: a nominal model, IAE_c).
struct FitResult {
  Model model;
  std::vector<std::string> sources;
  std::vector<double> iae;                   // per recording (eq. 20), mm·s
  std::vector<double> nrmse;                 // per recording (eq. 19), %
  std::vector<std::vector<double>> response; // model output per recording, absolute mm
  double iae_total = 0.0;                    // Σ iae (IAE_c, eq. 21)
  // The operating point of each recording the fit used: the data's y0, or with the
  // least-squares criterion its jointly fitted value (the responses and metrics use it).
  std::vector<double> y0_mm;
  // The minimised criterion: iae_total, or with least squares Σ h Σ (ŷ − y)², mm²·s.
  double cost_total = 0.0;
  int evaluations = 0;                       // cost evaluations spent
  int simulations = 0;                       // GL simulations spent (all recordings)
  bool converged = true;                     // false: an optimiser stopped on a limit/failure
  std::string message;                       // optimiser status, for reports
  // How sure the fit is (docs/reduced-models.md, "How sure a fit is"): from the least-squares
  // Jacobian of the output residuals (model − recording, every sample of every recording) by
  // forward differences, with the output offsets of the least-squares criterion as nuisance
  // parameters, and the residuals' autocorrelation taken into account (core/statistics.hpp: the
  // batch-means sandwich covariance). For the IAE criterion it is the least-squares figure at the
  // IAE optimum (for Gaussian noise the IAE estimate scatters about sqrt(π/2) ≈ 1.25 times more).
  // One entry per parameter of parameter_names(model.kind), in that order; empty where not
  // computed (the fits inside a γ sweep, whose best fit has them), NaN where the model could not
  // be simulated a step away from the fit.
  std::vector<std::string> parameter_names;
  // Standard deviation, parameter units (K as in model.p). 0 for a parameter held fixed (bounds
  // lo == hi, a fixed start, the γ of a sweep): it was not fitted. +inf where the recordings do
  // not determine it (an exact trade-off with another parameter, or no dependence at all).
  std::vector<double> std;
  // The part of std due to the model's time step (fit_statistics.cpp: twice the shift of the
  // optimum were the model computed at half the step); std combines it with the statistical part
  // as a root sum of squares. 0 for the integer-order models, which are simulated exactly.
  std::vector<double> numerical_std;
  // Correlations between the estimates; NaN in the rows and columns of fixed or undetermined
  // parameters.
  std::vector<std::vector<double>> correlation;
  // The sandwich's variances over the white-noise ones (≥ 1): how much the residuals'
  // autocorrelation widened the std; NaN where not computed.
  double inflation = std::numeric_limits<double>::quiet_NaN();
};

// What fitting `kind` to these recordings `fits` times over takes, known before it starts: the
// multiply-adds of the model simulations, about 300 simulations of every recording a fit (the
// least-squares polish on the whole record; the searches run on at most search_samples), each
// samples × memory terms for a fractional model (Grünwald–Letnikov), samples × 20 log²(samples)
// with the full memory, samples × 10 for an integer-order one (exact zero-order hold). Past
// kMaxFitOperations (about two minutes here) the CLI refuses the fit unless --allow-long.
double estimate_fit_operations(ModelKind kind, const std::vector<ExperimentData>& data, const FitOptions& options,
                               double fits = 1.0);
inline constexpr double kMaxFitOperations = 2.0e11;

// Fits `kind` to one recording. Throws InputError naming the recording (missing y_up for a
// nonlinear model), one with fewer than twice as many samples as the model has unknowns, or
// naming the bound that excludes every feasible model.
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
  [[nodiscard]] Status validate() const;  // ok, or one line naming the field ("step = 0: ...")
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
