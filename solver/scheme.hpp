// The finite-volume kernels of one Runge–Kutta stage on one reach, written as loops over
// contiguous arrays so the compiler vectorises them. Two section "ops" types give a rectangular
// fast path (no square root for the depth, c = sqrt(g h)) and the general trapezoid.
//
// Stage = (1) primitives h, u, η per cell; (2) limited slopes (MUSCL, generalised minmod on η, h, u;
// van Leer 1979); (3) interior face fluxes with hydrostatic reconstruction (Audusse, Bouchut,
// Bristeau, Klein & Perthame 2004, SIAM J. Sci. Comput. 25(6) 2050–2065) and HLL; the caller fills
// the two end faces from boundaries or links; (4) the update with the well-balanced centred source
// and semi-implicit friction, combined Heun-style with the start-of-step state.
#pragma once

#include <algorithm>
#include <cmath>

#include "solver/flux.hpp"
#include "solver/reach.hpp"

namespace canalsim::solver {

// Rectangular section of width b.
struct RectangularOps {
  double b, inv_b, g;
  double area(double h) const { return b * h; }
  double depth(double a) const { return a * inv_b; }
  double pressure(double h) const { return 0.5 * g * b * h * h; }  // g I1
  double celerity(double h) const { return std::sqrt(g * h); }
  double mean_area(double h1, double h2) const { return 0.5 * b * (h1 + h2); }
  double perimeter(double h) const { return b + 2.0 * h; }
};

// Trapezoid (general path).
struct TrapezoidalOps {
  double b, m, g, perimeter_factor;  // perimeter_factor = 2 sqrt(1 + m²)
  double area(double h) const { return h * (b + m * h); }
  double depth(double a) const { return 2.0 * a / (b + std::sqrt(b * b + 4.0 * m * a)); }
  double pressure(double h) const { return g * h * h * (0.5 * b + m * h * (1.0 / 3.0)); }
  double celerity(double h) const {
    const double t = b + 2.0 * m * h;
    return t > 0.0 ? std::sqrt(g * h * (b + m * h) / t) : 0.0;
  }
  double mean_area(double h1, double h2) const {
    return 0.5 * b * (h1 + h2) + m * (h1 * h1 + h1 * h2 + h2 * h2) * (1.0 / 3.0);
  }
  double perimeter(double h) const { return b + perimeter_factor * h; }
};

struct StageSettings {
  bool second_order = true;
  double theta = 1.0;      // limiter parameter
  double dry_depth = 1e-10;
};

struct UpdateSettings {
  double dt = 0.0;
  double alpha = 0.0;      // new = alpha U0 + (1 - alpha) (U + dt L(U))
  double dry_depth = 1e-10;
  double friction = 0.0;   // g n²
};

struct UpdateResult {
  double min_area;     // smallest new area (negative: positivity lost)
  double checksum;     // Σ (A + Q): non-finite iff some value is
  double lateral;      // Σ q_l,eff over cells [m²/s] (times dx dt: volume)
};

// Generalised minmod slope of a_{i-1}, a_i, a_{i+1} (θ in [1, 2]).
inline double limited_slope(double am, double a0, double ap, double theta) {
  const double d1 = theta * (a0 - am), d2 = theta * (ap - a0), dc = 0.5 * (ap - am);
  const double lo = std::min(std::min(d1, d2), dc), hi = std::max(std::max(d1, d2), dc);
  return d1 > 0.0 && d2 > 0.0 ? lo : (d1 < 0.0 && d2 < 0.0 ? hi : 0.0);
}

inline void end_slopes(const double* h, const double* eta, const double* u, double* dh, double* deta,
                       double* du, int end, int inner, double dry) {
  const bool wet = h[end] > dry && h[inner] > dry;
  // d/dx·dx of the one-sided difference; sign so that slope = value(i+1) − value(i) direction.
  const double sign = end < inner ? 1.0 : -1.0;
  const double d_h = sign * (h[inner] - h[end]);
  dh[end] = wet ? std::clamp(d_h, -2.0 * h[end], 2.0 * h[end]) : 0.0;
  deta[end] = wet ? sign * (eta[inner] - eta[end]) : 0.0;
  du[end] = wet ? sign * (u[inner] - u[end]) : 0.0;
}

struct ReachKernels {
  // Steps (1)–(3). Returns the largest wave speed over interior faces.
  template <class Ops>
  static double interior_fluxes(Reach& r, const Ops& ops, const StageSettings& s) {
    const int n = r.cells_;
    const double* __restrict a = r.area_.data();
    const double* __restrict q = r.discharge_.data();
    const double* __restrict z = r.bed_.data();
    double* __restrict h = r.h_.data();
    double* __restrict u = r.u_.data();
    double* __restrict eta = r.eta_.data();
    double* __restrict dh = r.dh_.data();
    double* __restrict du = r.du_.data();
    double* __restrict deta = r.deta_.data();
    const double dry = s.dry_depth;
    for (int i = 0; i < n; ++i) {
      const double hi = std::max(ops.depth(a[i]), 0.0);
      h[i] = hi;
      u[i] = hi > dry ? q[i] / a[i] : 0.0;
      eta[i] = z[i] + hi;
    }
    if (s.second_order) {
      const double th = s.theta;
      // End cells keep zero slopes (first order next to boundaries and links).
      for (int i = 1; i < n - 1; ++i) {
        dh[i] = limited_slope(h[i - 1], h[i], h[i + 1], th);
        deta[i] = limited_slope(eta[i - 1], eta[i], eta[i + 1], th);
        du[i] = limited_slope(u[i - 1], u[i], u[i + 1], th);
      }
      // End cells: the one-sided difference towards the interior when both cells are wet (so the
      // boundary face sees a second-order state and a bed extrapolated to the end, which keeps
      // steady friction profiles second order up to the boundary); zero slope next to dry cells,
      // which keeps lake-at-rest exact at shores. The depth slope is clipped to keep h ± dh/2 >= 0.
      end_slopes(h, eta, u, dh, deta, du, 0, 1, dry);
      end_slopes(h, eta, u, dh, deta, du, n - 1, n - 2, dry);
    }
    double* __restrict fm = r.face_mass_.data();
    double* __restrict fl = r.face_momentum_left_.data();
    double* __restrict fr = r.face_momentum_right_.data();
    double smax = 0.0;
    for (int f = 1; f < n; ++f) {
      const int L = f - 1, R = f;
      // Reconstructed values at the face from each side.
      const double hm = h[L] + 0.5 * dh[L], etam = eta[L] + 0.5 * deta[L];
      const double hp = h[R] - 0.5 * dh[R], etap = eta[R] - 0.5 * deta[R];
      const double um = u[L] + 0.5 * du[L], up = u[R] - 0.5 * du[R];
      // Hydrostatic reconstruction: one bed level per face, depths that keep η.
      const double zface = std::max(etam - hm, etap - hp);
      const double hl = std::max(0.0, etam - zface);
      const double hr = std::max(0.0, etap - zface);
      const PointState left{ops.area(hl), hl > dry ? um : 0.0, ops.pressure(hl), ops.celerity(hl)};
      const PointState right{ops.area(hr), hr > dry ? up : 0.0, ops.pressure(hr), ops.celerity(hr)};
      const Flux flux = hll_flux(left, right);
      fm[f] = flux.mass;
      // Each side sees the pressure of its own reconstructed depth (Audusse et al. 2004, eq. 2.6).
      fl[f] = flux.momentum + (ops.pressure(hm) - left.pressure);
      fr[f] = flux.momentum + (ops.pressure(hp) - right.pressure);
      smax = std::max(smax, flux.max_speed);
    }
    return smax;
  }

  // Step (4). The centred source g Ā (z_left − z_right) with Ā = (I1(h_right) − I1(h_left)) /
  // (h_right − h_left) cancels the pressure difference of a lake at rest exactly (Audusse et al.
  // 2004, §3); friction Q ← Q* / (1 + dt g n² |Q| / (A R^{4/3})) is linearly implicit, so it
  // damps without bound but never reverses the flow (e.g. Liang & Marche 2009).
  template <class Ops, bool kFriction>
  static UpdateResult update(Reach& r, const Ops& ops, const UpdateSettings& s) {
    const int n = r.cells_;
    double* __restrict a = r.area_.data();
    double* __restrict q = r.discharge_.data();
    const double* __restrict a0 = r.area0_.data();
    const double* __restrict q0 = r.discharge0_.data();
    const double* __restrict h = r.h_.data();
    const double* __restrict u = r.u_.data();
    const double* __restrict dh = r.dh_.data();
    const double* __restrict deta = r.deta_.data();
    const double* __restrict ql = r.lateral_inflow_.data();
    const double* __restrict fm = r.face_mass_.data();
    const double* __restrict fl = r.face_momentum_left_.data();
    const double* __restrict fr = r.face_momentum_right_.data();
    const double dt = s.dt, alpha = s.alpha, beta = 1.0 - alpha, dry = s.dry_depth;
    const double dt_dx = dt / r.dx_;
    const double g = ops.g;
    double min_area = INFINITY, checksum = 0.0, lateral = 0.0;
    for (int i = 0; i < n; ++i) {
      const double hleft = h[i] - 0.5 * dh[i], hright = h[i] + 0.5 * dh[i];
      const double source = g * ops.mean_area(hleft, hright) * (dh[i] - deta[i]);
      const double qlat = h[i] > dry ? ql[i] : std::max(ql[i], 0.0);
      const double a_star = a[i] - dt_dx * (fm[i + 1] - fm[i]) + dt * qlat;
      double q_star = q[i] - dt_dx * (fl[i + 1] - fr[i] - source) + dt * std::min(qlat, 0.0) * u[i];
      const double h_star = ops.depth(std::max(a_star, 0.0));
      if constexpr (kFriction) {
        // k from the stage's own state (not Q*): a steady state then satisfies the discrete
        // momentum balance L(U) = k(U) Q exactly, for any dt.
        const double radius = a[i] / ops.perimeter(h[i]);
        const double k = h[i] > dry ? s.friction * std::abs(q[i]) / (a[i] * radius * std::cbrt(radius)) : 0.0;
        q_star /= 1.0 + dt * k;
      }
      q_star = h_star > dry ? q_star : 0.0;
      const double a_new = alpha * a0[i] + beta * a_star;
      const double q_new = alpha * q0[i] + beta * q_star;
      a[i] = a_new;
      q[i] = q_new;
      min_area = std::min(min_area, a_new);
      checksum += a_new + q_new;
      lateral += qlat;
    }
    return {min_area, checksum, lateral};
  }
};

}  // namespace canalsim::solver
