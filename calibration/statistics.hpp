// What a calibration's optimum says about its parameters, as PEST and Pyomo parmest report it:
// covariance from the Jacobian, standard deviations, correlations, composite scaled sensitivities
// and the parameters the recordings cannot separate, named in words.
#pragma once

#include <string>
#include <vector>

#include "calibration/parameters.hpp"
#include "core/statistics.hpp"

namespace canalsim::calibration {

struct ParameterStatistics {
  std::vector<double> std;                       // parameter units; +inf when not determined
  std::vector<std::vector<double>> correlation;  // p × p; NaN for an undetermined parameter
  std::vector<double> sensitivity;               // composite scaled sensitivity
  double inflation = 1.0;                        // variance of the sandwich / the white-noise one
  struct Unidentified {
    std::vector<std::string> parameters;
    std::string reason, determined;
  };
  std::vector<Unidentified> unidentified;
};

// `jacobian`: N × p row-major, of the weighted residuals in the search coordinates `z`;
// `residuals`: the weighted residuals at the optimum; `series`: the unweighted residual series
// (for the autocorrelation correction). The covariance C_z in the search coordinates is
// core/statistics.hpp's least_squares_covariance: the batch-means sandwich B M B over blocks of
// 2τ samples (τ: integrated autocorrelation time, Geyer 1992), s² B for white residuals and
// larger for a smooth, model-form residual, never below s² B; `inflation` is its mean ratio to
// s² B. Directions of the column-scaled JᵀJ whose eigenvalue is below 1e-9 of the largest are not
// determined (exact trade-offs): their parameters get std = +inf and are named with the
// combination that is determined. Standard deviations in parameter units by the delta method
// (log: σ_v = v σ_z). Pairs with |correlation| > 0.95 and parameters with a relative std above
// 50 % are named too, relative to |v_j| for log parameters and to max(|v_j|, 10 steps) for
// linear ones (offsets sit near zero). Composite scaled sensitivity: sqrt(Σ_i (J_ij s_j)² / N),
// s_j = 1 for log parameters (a unit of log), max(|v_j|, 10 steps) for linear ones.
ParameterStatistics parameter_statistics(const std::vector<Parameter>& parameters, const std::vector<double>& z,
                                         const std::vector<double>& jacobian, const std::vector<double>& residuals,
                                         const std::vector<std::vector<double>>& series);

// The Gauss–Newton shift of the optimum when the residuals change: core/statistics.hpp.
using canalsim::optimum_shift;

}  // namespace canalsim::calibration
