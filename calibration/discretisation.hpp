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
//
// The grid-converged estimate (ParameterEstimate::converged) extrapolates the move on twice the
// cells: θ_∞ ≈ θ_N + (θ_2N − θ_N) · 2^p / (2^p − 1), the value a model without discretisation
// error would calibrate to — the one to compare with a measured coefficient, or to carry to a
// model on another grid. It uses the FIRST iteration's move, (JᵀJ)⁻¹ Jᵀ r_2N(θ_N): the linear
// response of the optimum to the change of model (Jᵀ r_N = 0 at the optimum), defined without an
// iteration count. Further iterations with the held Jacobian do not converge along a nearly
// singular direction: on the laboratory canal 1, 2, 3, 5 and 8 of them put the converged Cd
// submerged at −0.6, +1.8, +4.0, +7.8 and +12.1 % from the truth (docs/calibration.md) — a
// wander the numerical std keeps (it is how ill-determined the move is), an estimate must not.
//
// The order p = 1 (kGridOrder): the gate laws see the depth of the cell next to the gate, half a
// cell from it, and a sensor in the last cell sits half a cell from the downstream gate — errors
// proportional to the cell size. Measured on the laboratory canal (docs/calibration.md), the
// linear-response moves 100 -> 200 and 200 -> 400 cells against an 800-cell truth shrink by the
// ratios given there; p = 1 is the full first-order correction, and the numerical std keeps its
// size as the uncertainty of the extrapolation.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "calibration/problem.hpp"

namespace canalsim::calibration {

// The order of the leading discretisation error in the calibrated parameters (header comment).
constexpr double kGridOrder = 1.0;
// Richardson's factor 2^p / (2^p − 1): θ_N − θ_∞ ≈ factor · (θ_N − θ_2N).
inline double richardson_factor(double order) { return std::exp2(order) / (std::exp2(order) - 1.0); }

struct DiscretisationShift {
  std::string name;            // "twice the cells", "the other limiter", "half the Courant number"
  double weight = 1.0;         // factor on the move in the uncertainty (Richardson: 2 for the cells)
  std::vector<double> shift;   // θ_alternative − θ per parameter, parameter units
  std::vector<double> linear_response;  // the first iteration's move (the grid-converged estimate's)
  double cost = 0.0;           // weighted cost per sample of the alternative at the optimum
  // The alternative's prediction at the optimum, for the grid check (calibrate() clears it).
  std::vector<Channels> at_optimum;
};

// `z`: the optimum (search coordinates), `jacobian`: row-major N × p at z. `iterations` >= 1:
// Gauss–Newton iterations per alternative, each one simulation per recording.
// `twice_the_cells_at_z`: the prediction on twice the cells at z when the caller already has it.
std::vector<DiscretisationShift> discretisation_shifts(ReplayProblem& problem, const std::vector<double>& z,
                                                       const std::vector<double>& jacobian, int iterations = 2,
                                                       const std::vector<Channels>* twice_the_cells_at_z = nullptr);

// The scenario of `problem` at z on twice the cells (the first alternative above).
scenarios::Scenario twice_the_cells(const ReplayProblem& problem, const std::vector<double>& z);

// The numerical uncertainty of every parameter: sqrt(Σ_a (weight_a shift_a)²).
std::vector<double> numerical_uncertainty(const std::vector<DiscretisationShift>& shifts, std::size_t parameters);

// The grid-converged estimates: `values` (parameter units) moved by Richardson's extrapolation
// of the linear response on twice the cells, θ + factor · (θ_2N − θ), held within the bounds;
// `values` unchanged when `shifts` has no re-estimate on twice the cells.
std::vector<double> grid_converged(const std::vector<Parameter>& parameters, const std::vector<double>& values,
                                   const std::vector<DiscretisationShift>& shifts);

}  // namespace canalsim::calibration
