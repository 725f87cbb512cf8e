// How much of a calibration's estimate the model's numerics decide rather than the recordings.
//
// A calibrated value is the one that makes THIS discretisation (cells, limiter, Courant number)
// reproduce the recordings. The real canal, or another simulator, is a different discretisation
// or none at all, and the optimum moves with it: on the laboratory canal, twice the cells move
// Cd free by ~5 % when the statistical std is 0.5 %. The statistical std cannot see this: it is
// an error of the model's form, not noise. What the calibration can measure is how far the
// estimate moves when the model's own numerical choices change, each a choice as defensible as
// the scenario's:
//
//   twice the cells        re-estimated on the refined grid; Richardson extrapolation turns the
//                          move θ_N − θ_2N into the N-cell estimate's distance from the converged
//                          one, (θ_N − θ_2N) · 2^p / (2^p − 1), with p = 1: the scheme is second
//                          order in smooth flow but first order at the gate's kinks, the
//                          hydraulic jump and wherever its limiter clips (factor 2);
//   the other limiter      van Leer <-> generalised minmod (docs/numerics.md);
//   half the Courant number.
//
// Each re-estimate is a few Gauss–Newton iterations on the alternative model with the Jacobian
// of the optimum held fixed (the alternatives are small perturbations of the model, so the
// Jacobian barely changes, and each iteration costs one simulation per recording instead of a
// whole Levenberg–Marquardt run). The moves combine in quadrature into the numerical uncertainty
// that calibrate() adds to the statistical std (ParameterEstimate::grid_shift).
#pragma once

#include <string>
#include <vector>

#include "calibration/problem.hpp"

namespace canalsim::calibration {

struct DiscretisationShift {
  std::string name;            // "twice the cells", "the other limiter", "half the Courant number"
  double weight = 1.0;         // factor on the move in the uncertainty (Richardson: 2 for the cells)
  std::vector<double> shift;   // θ_alternative − θ per parameter, parameter units
  double cost = 0.0;           // weighted cost per sample of the alternative at the optimum
  // The alternative's prediction at the optimum, for the grid check (calibrate() clears it).
  std::vector<Channels> at_optimum;
};

// `z`: the optimum (search coordinates), `jacobian`: row-major N × p at z. `iterations` >= 1:
// Gauss–Newton iterations per alternative, each one simulation per recording.
std::vector<DiscretisationShift> discretisation_shifts(ReplayProblem& problem, const std::vector<double>& z,
                                                       const std::vector<double>& jacobian, int iterations = 2);

// The numerical uncertainty of every parameter: sqrt(Σ_a (weight_a shift_a)²).
std::vector<double> numerical_uncertainty(const std::vector<DiscretisationShift>& shifts, std::size_t parameters);

}  // namespace canalsim::calibration
