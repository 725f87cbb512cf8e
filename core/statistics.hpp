// How sure a least-squares estimate is, for any fit of parameters to residual series: the
// covariance from the Jacobian at the optimum, corrected for residuals that are not white, and
// the standard deviations and correlations it gives. Written once here for the two fitters that
// report it — calibration (calibration/statistics.hpp, which adds its parameter transforms and
// names what is not identified) and the reduced-model fits (reduced_models/identification.hpp) —
// and independent of what the parameters are.
//
// Residuals that a model leaves are rarely white: a model that cannot represent the data leaves a
// smooth, long-correlated residual, and the textbook covariance s² (JᵀJ)⁻¹ then claims far more
// certainty than the data hold. Two corrections, both measured from the residuals themselves:
//   the integrated autocorrelation time τ of each series (Geyer 1992, initial positive sequence),
//   which says how many independent samples a series is worth; and
//   the batch-means sandwich covariance B M B (a heteroscedasticity- and autocorrelation-
//   consistent estimator, e.g. Newey & West 1987; Flegal & Jones 2010 for batch means), over
//   blocks of 2τ consecutive samples.
#pragma once

#include <cstddef>
#include <vector>

namespace canalsim {

// The sample autocorrelation r(k) of a series about its mean, k = 0..max_lag: r(0) = 1, all zero
// for a constant series. The residual tests of the diagnosis and the report's autocorrelation
// plots read the same numbers.
std::vector<double> autocorrelation(const std::vector<double>& series, int max_lag);

// τ = 1 + 2 Σ ρ_k of one series, summed over the initial positive sequence of adjacent pairs
// (Geyer 1992) up to a quarter of the series; 1 for a series shorter than 3 or constant.
double integrated_autocorrelation_time(const std::vector<double>& series);

// N / N_eff of residual series: each series' effective size n / τ, at least 1. A residual left by
// a model that cannot represent the data is smooth and long-correlated; τ then inflates the
// covariance accordingly, where a lag-one (AR(1)) correction would not.
double autocorrelation_inflation(const std::vector<std::vector<double>>& series);

// The covariance of least-squares estimates, in the coordinates of the Jacobian's columns.
struct LeastSquaresCovariance {
  std::size_t parameters = 0;
  std::vector<double> matrix;      // parameters × parameters, row-major
  std::vector<bool> undetermined;  // moved by a null direction (below): the data do not fix it
  // 1 / sqrt((JᵀJ)_jj), 0 for a column of zeros: the scaling under which the null directions are
  // found (so that parameters of different units are compared fairly).
  std::vector<double> column_scale;
  // Unit eigenvectors of the column-scaled JᵀJ whose eigenvalue is below 1e-9 of the largest:
  // combinations of the parameters the data do not depend on (exact trade-offs), in scaled
  // coordinates (multiply component j by column_scale[j] for the parameters' own).
  std::vector<std::vector<double>> null_directions;
  // The sandwich's variances over the white-noise ones s² B, averaged over the parameters; ≥ 1.
  double inflation = 1.0;

  double operator()(std::size_t a, std::size_t b) const { return matrix[a * parameters + b]; }
};

// `jacobian`: N × `parameters` row-major, of the (weighted) residuals at the optimum; `residuals`: those
// residuals (N); `series`: the unweighted residual series, one per recording, whose lengths add
// up to N and split the rows (for the autocorrelation correction and the blocks).
//   C = B M B,  B = (JᵀJ)⁺,  M = Σ_b g_b g_bᵀ,  g_b = J_bᵀ r_b
// summed over blocks of 2τ consecutive samples of each series, times n_b / (n_b − p) for the
// degrees of freedom: s² B for white residuals, and larger for a smooth, model-form residual;
// never below s² B (s² = rᵀr / (N − p)). Where the series do not split the rows, s² B times the
// autocorrelation inflation. The pseudo-inverse is taken on the column-scaled JᵀJ, dropping the
// null directions.
LeastSquaresCovariance least_squares_covariance(const std::vector<double>& jacobian, std::size_t parameters,
                                                const std::vector<double>& residuals,
                                                const std::vector<std::vector<double>>& series);

// sqrt of the diagonal, +inf for an undetermined parameter (same coordinates as the covariance).
std::vector<double> standard_deviations(const LeastSquaresCovariance& covariance);

// C_ab / sqrt(C_aa C_bb), 1 on the diagonal; NaN in the rows and columns of undetermined
// parameters, 0 for a pair one of which has zero variance.
std::vector<std::vector<double>> correlations(const LeastSquaresCovariance& covariance);

// The Gauss–Newton shift of the optimum when the residuals change by `change` (N): the
// least-squares δ minimising |change + J δ| (`jacobian` N × p, row-major), by the pseudo-inverse
// of least_squares_covariance: directions J does not determine are left unmoved. How far the
// estimates would move were the model computed otherwise: calibration's grid check (twice the
// cells), a reduced model's finer time step.
std::vector<double> optimum_shift(const std::vector<double>& jacobian, const std::vector<double>& change,
                                  std::size_t parameters);

}  // namespace canalsim
