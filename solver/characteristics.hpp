// Characteristics at an end face: the tools a boundary (a sluice gate, a weir, a fixed level)
// uses to find the state on the face from the one Riemann invariant that leaves the interior.
//
// For a prismatic channel the Saint-Venant equations have the Riemann invariants
//
//   w± = u ± Φ(h),   Φ(h) = ∫_0^h sqrt(g T(s)/A(s)) ds   (= 2c for a rectangle)
//
// carried along dx/dt = u ± c (Cunge, Holly & Verwey 1980, §2.3; Toro 2001, ch. 5 for the
// rectangular case). At the downstream end of a reach the C+ invariant w+ arrives from the
// interior; at the upstream end it is C−. A subcritical boundary imposes one more relation (a
// level, a discharge, a gate law Q = f(h_face, t)); the face state (h_b, u_b) solves
//
//   u_b = w_out ∓ Φ(h_b)  (− at the downstream end, + at the upstream end)  and the relation,
//
// and the face flux is the exact flux of that state, F = (A_b u_b, A_b u_b² + g I1(h_b)), so the
// mass the structure passes is exactly the discharge it computed.
#pragma once

#include <functional>

#include "solver/flux.hpp"
#include "solver/section.hpp"

namespace canalsim::solver {

enum class End { upstream, downstream };

// The interior state next to an end face: the adjacent cell's MUSCL reconstruction extrapolated
// to the face (the cell average at first order or when the neighbour is dry), so that a boundary
// sees the same depth the cell's own flux balance uses (this keeps lake-at-rest exact next to
// walls and levels). `bed` is the reconstructed bed at the face, η_face − h_face.
struct InteriorState {
  double area;       // A [m²]
  double discharge;  // Q [m³/s], positive downstream
  double depth;      // h [m]
  double bed;        // z [m]
  double velocity() const { return area > 0.0 ? discharge / area : 0.0; }
};

// Invariant that leaves the interior towards the face at `end`: u + Φ(h) downstream, u − Φ(h)
// upstream.
double outgoing_invariant(const Section& section, double gravity, End end, double depth,
                          double velocity);
inline double outgoing_invariant(const Section& section, double gravity, End end,
                                 const InteriorState& cell) {
  return outgoing_invariant(section, gravity, end, cell.depth, cell.velocity());
}
// Face velocity compatible with invariant w at face depth h: w − Φ(h) downstream, w + Φ(h)
// upstream.
double velocity_from_invariant(const Section& section, double gravity, End end, double invariant,
                               double depth);

// True when the interior flow leaves through `end` supercritically (Froude > 1 towards the face);
// then no condition can be imposed there and the face state is the interior state.
bool is_supercritical_outflow(const Section& section, double gravity, End end,
                              const InteriorState& cell);

// Exact flux of a face state (depth h, discharge Q) in the given section.
Flux face_state_flux(const Section& section, double gravity, double depth, double discharge);

struct FaceState {
  double depth = 0.0;      // h_b [m]
  double discharge = 0.0;  // Q_b [m³/s]
  bool found = false;      // false: no face depth satisfies both relations in the search range
};

// A discharge relation at the face, Q = law(h_b) (a gate law, a fixed inflow, a weir).
using DischargeLaw = std::function<double(double face_depth)>;

// Solves  A(h_b) · velocity_from_invariant(w_out, h_b) = law(h_b)  for h_b in (0, max_depth], with
// w_out the outgoing invariant of `cell`. The search scans down from max_depth (default: a depth
// well above any the interior can reach) on a geometric grid and takes the deepest root, i.e. the
// subcritical (tranquil) branch, then refines it by Illinois false position to ~1e-14 relative
// (about 60 evaluations of `law` in all). `found` is false when the residual has no sign change;
// `depth` is then the scan point with the smallest |residual|.
FaceState solve_face_state(const Section& section, double gravity, End end,
                           const InteriorState& cell, const DischargeLaw& law,
                           double max_depth = 0.0);

}  // namespace canalsim::solver
