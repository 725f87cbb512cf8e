// Numerical flux kernels for the 1D Saint-Venant equations in conservative form
//
//   ∂A/∂t + ∂Q/∂x = q_l
//   ∂Q/∂t + ∂(Q²/A + g I1(h))/∂x = -g A ∂z/∂x - g A S_f
//
// with the flux F(U) = (Q, Q²/A + g I1) of U = (A, Q). Every kernel has the same signature: two
// point states (left and right of a face, already hydrostatically reconstructed by the caller)
// in, the face flux and the largest signal speed out. The kernels never look at the section: the
// caller passes the pressure term p = g I1(h) and the celerity c = sqrt(g A/T), so one kernel
// serves rectangles and trapezoids (the same split as Basilisk's src/riemann.h and Clawpack's
// rp1_shallow_*). Dry states (A = 0) must have u = 0, p = 0, c = 0.
#pragma once

#include <algorithm>
#include <cmath>

namespace canalsim::solver {

// State on one side of a face.
struct PointState {
  double area;       // A [m²]
  double velocity;   // u = Q/A [m/s], 0 when dry
  double pressure;   // g I1(h) [m⁴/s²]
  double celerity;   // c = sqrt(g A / T) [m/s], 0 when dry
};

// Flux through a face: mass (discharge, m³/s) and momentum (m⁴/s²), plus the largest |wave
// speed| used, for the CFL condition.
struct Flux {
  double mass;
  double momentum;
  double max_speed;
};

// Exact flux of a single state, F(U) = (A u, A u² + g I1).
inline Flux physical_flux(const PointState& s) {
  const double q = s.area * s.velocity;
  return {q, q * s.velocity + s.pressure, std::abs(s.velocity) + s.celerity};
}

// HLL flux (Harten, Lax & van Leer 1983; Toro, "Riemann Solvers and Numerical Methods for Fluid
// Dynamics", 3rd ed., §10.3):
//
//   F = (s_R⁺ F_L − s_L⁻ F_R + s_L⁻ s_R⁺ (U_R − U_L)) / (s_R⁺ − s_L⁻),
//   s_L⁻ = min(s_L, 0),  s_R⁺ = max(s_R, 0),
//
// with Davis' wave-speed estimates s_L = min(u_L − c_L, u_R − c_R), s_R = max(u_L + c_L, u_R + c_R),
// replaced at a dry side by the dry-front speed u ∓ 2c of the wet side (Toro 2001, "Shock-capturing
// methods for free-surface shallow flows", §10.7). Clamping the speeds at zero makes the formula
// return F_L or F_R for supersonic faces without branches, so the loop that calls it vectorises.
inline Flux hll_flux(const PointState& l, const PointState& r) {
  const double sl_wet = std::min(l.velocity - l.celerity, r.velocity - r.celerity);
  const double sr_wet = std::max(l.velocity + l.celerity, r.velocity + r.celerity);
  const double sl = l.area > 0.0 ? sl_wet : r.velocity - 2.0 * r.celerity;
  const double sr = r.area > 0.0 ? sr_wet : l.velocity + 2.0 * l.celerity;
  const double sm = std::min(sl, 0.0);
  const double sp = std::max(sr, 0.0);
  const double ql = l.area * l.velocity, qr = r.area * r.velocity;
  const double fl = ql * l.velocity + l.pressure, fr = qr * r.velocity + r.pressure;
  const double denom = sp - sm;
  // Both sides dry: denom = 0 and every flux is 0; avoid 0/0 without a branch.
  const double inv = denom > 0.0 ? 1.0 / denom : 0.0;
  Flux f;
  f.mass = (sp * ql - sm * qr + sm * sp * (r.area - l.area)) * inv;
  f.momentum = (sp * fl - sm * fr + sm * sp * (qr - ql)) * inv;
  f.max_speed = std::max(sp, -sm);
  return f;
}

// Rusanov (local Lax–Friedrichs) flux: F = (F_L + F_R)/2 − a (U_R − U_L)/2, a = max |u| + c.
// More diffusive than HLL; kept for comparison and as a fallback.
inline Flux rusanov_flux(const PointState& l, const PointState& r) {
  const double a = std::max(std::abs(l.velocity) + l.celerity, std::abs(r.velocity) + r.celerity);
  const double ql = l.area * l.velocity, qr = r.area * r.velocity;
  const double fl = ql * l.velocity + l.pressure, fr = qr * r.velocity + r.pressure;
  return {0.5 * (ql + qr) - 0.5 * a * (r.area - l.area),
          0.5 * (fl + fr) - 0.5 * a * (qr - ql), a};
}

using FluxKernel = Flux (*)(const PointState&, const PointState&);

}  // namespace canalsim::solver
