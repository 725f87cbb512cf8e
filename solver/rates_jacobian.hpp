// The Jacobian ∂L/∂U of the semi-discrete scheme (Canal::evaluate_rates) by coloured finite
// differences, shared by the steady-state Newton solver and the linearisation.
//
// Unknowns: the cells of all reaches in order, A and Q interleaved (U[2c] = A, U[2c+1] = Q), the
// layout of evaluate_rates. Cell c's rates depend on its two faces, and a face on the
// reconstructions (limited slopes) of its two cells, and a link or boundary face on the end
// cells of its reach(es): cells c-2..c+2. So columns 5 cells apart can be perturbed together and
// a Jacobian costs 2·5 residual evaluations whatever the grid size (Curtis, Powell & Reid 1974).
// (A missed dependence would show as a Newton that converges linearly, which
// tests/solver/steady_state_test would catch.)
#pragma once

#include <cstdint>
#include <vector>

#include "solver/canal.hpp"

namespace canalsim::solver {

inline constexpr int kRateStencil = 2;                  // half-width of the dependence, in cells
inline constexpr int kRateColours = 2 * kRateStencil + 1;  // cells this far apart share a colour

// Compressed sparse columns of the band: column j = 2c + m holds rows 2r, 2r+1 of the cells
// r = c-2..c+2 (within the grid), in increasing order.
struct RatesPattern {
  int unknowns = 0;
  std::vector<std::int64_t> column_start;  // unknowns + 1 entries
  std::vector<std::int64_t> row;
};
RatesPattern rates_jacobian_pattern(int cells);

// Writes U into the reaches; false (state partly written) if an area is negative or a value
// not finite.
bool load_state(Canal& canal, const double* u);
void store_state(const Canal& canal, double* u);

struct RatesJacobianOptions {
  // Step of unknown j: relative_step · max(|U_j|, scale[j]).
  double relative_step = 1e-7;
  LimiterKinks kinks = LimiterKinks::as_scheme;
};

// Fills values[k] (in the order of pattern.row) with forward differences of evaluate_rates at
// the state u, whose rates are f0; scale[j] is a typical size of unknown j. u is perturbed in
// place and restored; the canal holds u on return. Returns false if a perturbed state cannot be
// evaluated (negative area, non-finite rates): the values are then 0. *evaluations counts the
// rate evaluations.
bool rates_jacobian(Canal& canal, double time, double* u, const double* f0, const std::vector<double>& scale,
                    const RatesPattern& pattern, const RatesJacobianOptions& options, double* values,
                    int* evaluations);

}  // namespace canalsim::solver
