#include "solver/boundary.hpp"

#include <algorithm>
#include <cmath>

namespace canalsim::solver {
namespace {

PointState point_state(const Section& s, double g, double h, double u) {
  const double a = s.area(h);
  return {a, a > 0.0 ? u : 0.0, g * s.pressure_integral(h), s.celerity(h, g)};
}

PointState interior_point_state(const BoundaryInput& in) {
  return point_state(in.section, in.gravity, in.cell.depth, in.cell.velocity());
}

Flux interior_flux(const BoundaryInput& in) { return physical_flux(interior_point_state(in)); }

}  // namespace

Flux WallBoundary::flux(const BoundaryInput& in) const {
  const PointState inside = interior_point_state(in);
  PointState mirror = inside;
  mirror.velocity = -inside.velocity;
  Flux f = in.end == End::downstream ? hll_flux(inside, mirror) : hll_flux(mirror, inside);
  f.mass = 0.0;  // exact by symmetry; remove round-off
  return f;
}

Flux TransmissiveBoundary::flux(const BoundaryInput& in) const { return interior_flux(in); }

Flux FixedLevelBoundary::flux(const BoundaryInput& in) const {
  if (is_supercritical_outflow(in.section, in.gravity, in.end, in.cell)) return interior_flux(in);
  const double target = level_(in.time);
  const double h_b = std::max(0.0, is_depth_ ? target : target - in.cell.bed);
  const double w = outgoing_invariant(in.section, in.gravity, in.end, in.cell);
  const double u_b = velocity_from_invariant(in.section, in.gravity, in.end, w, h_b);
  return physical_flux(point_state(in.section, in.gravity, h_b, u_b));
}

Flux FixedDischargeBoundary::flux(const BoundaryInput& in) const {
  const double q = discharge_(in.time);
  const FaceState face = solve_face_state(in.section, in.gravity, in.end, in.cell,
                                          [q](double) { return q; });
  // Without a root (an outflow larger than the interior can supply), the critical depth of q is
  // the closest admissible face state; the mass flux is still exactly q.
  const double h_b = face.found ? face.depth : in.section.critical_depth(q, in.gravity);
  return face_state_flux(in.section, in.gravity, h_b, q);
}

Flux CriticalDepthBoundary::flux(const BoundaryInput& in) const {
  const Section& s = in.section;
  const double g = in.gravity;
  if (in.end == End::downstream && is_supercritical_outflow(s, g, in.end, in.cell))
    return interior_flux(in);
  const double w = outgoing_invariant(s, g, End::downstream, in.cell);
  if (in.end == End::upstream || w <= 0.0) {
    WallBoundary wall;
    return wall.flux(in);
  }
  // Solve c(h) + Φ(h) = w (monotone increasing in h) by bisection.
  double lo = 0.0, hi = std::max(in.cell.depth, 1e-6);
  while (s.celerity(hi, g) + s.characteristic_integral(hi, g) < w) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-14 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (s.celerity(mid, g) + s.characteristic_integral(mid, g) < w ? lo : hi) = mid;
  }
  const double h_b = 0.5 * (lo + hi);
  return physical_flux(point_state(s, g, h_b, s.celerity(h_b, g)));
}

LinkFlux ContinuousLink::flux(const LinkInput& in) const {
  const double g = in.gravity;
  const InteriorState& l = in.upstream_cell;
  const InteriorState& r = in.downstream_cell;
  // Hydrostatic reconstruction (Audusse et al. 2004) across the bed step at the link.
  const double z_face = std::max(l.bed, r.bed);
  const double hl = std::max(0.0, l.depth + l.bed - z_face);
  const double hr = std::max(0.0, r.depth + r.bed - z_face);
  // Each side evaluates the Riemann problem in its own section, so that at rest each sees its own
  // hydrostatic force (the walls of a width change take the difference); the one mass flux both
  // sides share is the mean of the two, which keeps the link exactly conservative.
  const Section& su = in.upstream_section;
  const Section& sd = in.downstream_section;
  const Flux fu = hll_flux(point_state(su, g, hl, l.velocity()), point_state(su, g, hr, r.velocity()));
  const Flux fd = hll_flux(point_state(sd, g, hl, l.velocity()), point_state(sd, g, hr, r.velocity()));
  LinkFlux out;
  out.mass = 0.5 * (fu.mass + fd.mass);
  out.momentum_upstream = fu.momentum + g * (su.pressure_integral(l.depth) - su.pressure_integral(hl));
  out.momentum_downstream = fd.momentum + g * (sd.pressure_integral(r.depth) - sd.pressure_integral(hr));
  out.max_speed = std::max(fu.max_speed, fd.max_speed);
  return out;
}

}  // namespace canalsim::solver
