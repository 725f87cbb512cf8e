// The design (steady, target-level) state of a canal of several pools, and what is derived from
// it before a run: design flows, each pool's gradually varied (backwater) profile, the opening of
// every gate with opening_m = "auto", and the coefficient of every orifice offtake.
//
// Design flows: the inflow of pool i minus its offtakes' design discharges is its outflow, which
// enters pool i+1. The head flow is the upstream inflow (kind "discharge"); otherwise the flows are
// summed upwards from a closed end (0) or a pump (its discharge).
//
// Backwater profile: with the depth at the check (the pool's downstream end x = L, where y_check
// is read) equal to the pool's target depth, the steady profile upstream follows the gradually varied flow
// equation (Chow 1959, Open-Channel Hydraulics, eq. 9-13; Henderson 1966, eq. 4.4)
//
//   dy/dx = (S0 − Sf) / (1 − Fr²),   Sf = n² Q² / (A² R^{4/3}),   Fr² = Q² T / (g A³),
//
// for the trapezoidal section, integrated upstream by classical RK4 with eight steps per cell.
// Q is piecewise constant (point offtakes); the depth is taken continuous across an offtake
// (the energy-conserving jump differs by the change of velocity head, < 4 mm in the ASCE canals).
//
// Automatic openings: the Swamee law of the gate (gates/sluice_gate.hpp) is inverted by bisection
// for the opening a with Q = b q(y1, y3, a), y1 and y3 measured from the sill as the solver's
// GateLink measures them: the link's face states are the reconstructed states at the pool ends,
// whose one-sided end slopes extrapolate each pool's linear bed to its end, and the sill is the
// higher of those two end beds. So y1 = the upstream pool's target depth (at x = L) and y3 = the
// next pool's design depth at x = 0, both above the sill (no bed step on a continuous bed). For
// the head gate y1 is the supply level. (Taking the sill at the end cells' centres instead would
// shift each drowned check's head by half a cell's bed drop on each side; with heads of a few
// centimetres that moves canal 2's levels by up to 3 cm.)
//
// Orifice offtakes: K = Q_design / (h_design − invert)^exponent, with h_design the profile depth at the
// offtake's cell (at x = L, the target depth, for an offtake at the pool's end), so the outlet
// delivers its design discharge at the design state.
#pragma once

#include <vector>

#include "gates/structures.hpp"
#include "scenarios/scenario.hpp"
#include "solver/section.hpp"

namespace canalsim::scenarios {

// Bed elevation at the centre of cell `cell` of a pool [m] (the solver's piecewise-constant bed).
double cell_bed_elevation(const PoolSpec& pool, int cell);
// The cell that holds an offtake at x (clamped to the pool).
int offtake_cell(const PoolSpec& pool, double x_m);
// Whether an offtake at x sits at the pool's downstream end (x = length_m), where it is withdrawn
// at the end face (solver/reach.hpp, fixed_end_withdrawal) rather than inside the last cell.
bool offtake_at_end(const PoolSpec& pool, double x_m);
// The gate geometry and law of a gate spec (the multiplier applies to the published coefficient).
gates::GateGeometry gate_geometry(const GateSpec& gate);

struct PoolFlows {
  double inflow = 0.0;   // [m³/s] entering the pool
  double outflow = 0.0;  // [m³/s] leaving through its downstream end
};
// Throws InputError when the flows are not determined (see the header comment) or inconsistent.
std::vector<PoolFlows> design_flows(const Scenario& scenario);

// Right-hand side dy/dx of the gradually varied flow equation at depth y [m] for discharge Q.
double gvf_slope(const solver::Section& section, double manning_n, double bed_slope, double discharge,
                 double depth, double gravity = 9.81);

// Steady depth profile of `pool` carrying `inflow` (less each offtake downstream of it), with
// `end_depth` at its downstream end x = L. Throws std::runtime_error naming the pool and x when the
// profile reaches critical flow (Fr² > 0.95) or the bed.
struct BackwaterProfile {
  std::vector<double> cell_depth;  // at the cell centres [m]
  double start_depth = 0.0;        // at x = 0 [m]
  double end_depth = 0.0;          // at x = L [m]
};
BackwaterProfile backwater_profile(const PoolSpec& pool, double inflow, double end_depth, double gravity = 9.81);

// The opening in [0, max_opening] that passes `discharge` [m³/s] with depths y1 upstream and y3
// downstream of the sill; throws std::runtime_error when even max_opening cannot.
double gate_opening_for(const gates::GateGeometry& gate, double discharge, double y1, double y3,
                        double max_opening);

// A copy of the scenario with automatic openings (auto_opening cleared), the coefficients of
// orifices that have none, and design profiles filled in (the scenario itself when it needs none
// of them, e.g. once resolved). Throws InputError naming the key.
Scenario resolve_design(const Scenario& scenario);

}  // namespace canalsim::scenarios
