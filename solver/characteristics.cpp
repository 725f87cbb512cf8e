#include "solver/characteristics.hpp"

#include "solver/illinois.hpp"

#include <algorithm>
#include <cmath>

namespace canalsim::solver {

double outgoing_invariant(const Section& section, double gravity, End end, double depth,
                          double velocity) {
  const double phi = section.characteristic_integral(depth, gravity);
  return end == End::downstream ? velocity + phi : velocity - phi;
}

double velocity_from_invariant(const Section& section, double gravity, End end, double invariant,
                               double depth) {
  const double phi = section.characteristic_integral(depth, gravity);
  return end == End::downstream ? invariant - phi : invariant + phi;
}

bool is_supercritical_outflow(const Section& section, double gravity, End end,
                              const InteriorState& cell) {
  if (cell.area <= 0.0) return false;
  const double u = cell.velocity();
  const double c = section.celerity(cell.depth, gravity);
  return end == End::downstream ? u >= c : u <= -c;
}

Flux face_state_flux(const Section& section, double gravity, double depth, double discharge) {
  const double h = std::max(depth, 0.0);
  const double a = section.area(h);
  const PointState s{a, a > 0.0 ? discharge / a : 0.0, gravity * section.pressure_integral(h),
                     section.celerity(h, gravity)};
  Flux f = physical_flux(s);
  f.mass = a > 0.0 ? discharge : 0.0;  // exactly the discharge passed, no round trip through u
  return f;
}

FaceState solve_face_state(const Section& section, double gravity, End end,
                           const InteriorState& cell, const DischargeLaw& law, double max_depth) {
  const double w = outgoing_invariant(section, gravity, end, cell);
  auto residual = [&](double h) {
    return section.area(h) * velocity_from_invariant(section, gravity, end, w, h) - law(h);
  };
  if (!(max_depth > 0.0)) {
    // From the invariant, |u_b| <= |w| + Φ(h_b); depth above h_i + (|u_i| + 2c_i)²/g is never
    // reached by a physical face state fed from this cell. Add margin and a floor.
    const double c = section.celerity(cell.depth, gravity);
    const double head = std::abs(cell.velocity()) + 2.0 * c;
    max_depth = 4.0 * (cell.depth + head * head / gravity) + 1e-3;
  }
  // Scan down from max_depth on a geometric grid (48 points over six decades, then 0): the first
  // sign change is the deepest root. Refine it by the Illinois variant of false position
  // (solver/illinois.hpp), which converges superlinearly, with a bisection every eighth trial
  // (at most 100 trials).
  constexpr int kScan = 48;
  const double ratio = std::pow(1e-6, 1.0 / (kScan - 1));
  FaceState best;
  double best_abs = INFINITY;
  double h_hi = max_depth, r_hi = residual(h_hi);
  for (int k = 1; k <= kScan; ++k) {
    const double h_lo = k == kScan ? 0.0 : max_depth * std::pow(ratio, k);
    const double r_lo = residual(h_lo);
    if (std::abs(r_hi) < best_abs) {
      best_abs = std::abs(r_hi);
      best.depth = h_hi;
    }
    if ((r_lo <= 0.0 && r_hi >= 0.0) || (r_lo >= 0.0 && r_hi <= 0.0)) {
      IllinoisOptions o;
      o.max_iterations = 100;
      o.relative_width = 1e-14;
      o.bisect_every = 8;
      const IllinoisResult root = illinois(residual, h_lo, h_hi, r_lo, r_hi, o);
      best.depth = 0.5 * (root.lo + root.hi);
      best.found = true;
      break;
    }
    h_hi = h_lo;
    r_hi = r_lo;
  }
  best.discharge = law(best.depth);
  return best;
}

}  // namespace canalsim::solver
