// The finite-volume kernels of one Runge–Kutta stage on one reach, written as loops over
// contiguous arrays so the compiler vectorises them. Two section "ops" types give a rectangular
// fast path (no square root for the depth, c = sqrt(g h)) and the general trapezoid.
//
// Stage = (1) primitives h, u, η per cell; (2) limited slopes (MUSCL on η, h, u, van Leer 1979;
// van Leer's harmonic limiter or the generalised minmod); (3) interior face fluxes with hydrostatic reconstruction (Audusse, Bouchut,
// Bristeau, Klein & Perthame 2004, SIAM J. Sci. Comput. 25(6) 2050–2065) and HLL; the caller fills
// the two end faces from boundaries or links; (4) the update with the well-balanced centred source
// and semi-implicit friction, combined Heun-style with the start-of-step state.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

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
  double depth(double a) const { return 2.0 * a / std::max(b + std::sqrt(b * b + 4.0 * m * a), 1e-300); }
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
  bool van_leer = true;    // van Leer's harmonic limiter; false: generalised minmod with theta
  double theta = 1.0;      // generalised minmod parameter
  double dry_depth = 1e-10;
  // Linearisation only (Canal::evaluate_rates with LimiterKinks::centred, docs/linearization.md):
  // where the one-sided differences d₋, d₊ of a cell are not both clearly of one sign
  // (d₋ d₊ <= (1e-5 · scale)², scale = the reach's largest depth, or its celerity for u), the
  // limiter's slope is replaced by the centred difference (d₋ + d₊)/2 — the limit of van Leer's
  // derivative on smooth monotone data — so that the finite-difference Jacobian is the same on
  // either side of the limiter's kink (flat stretches, extrema).
  bool centred_kinks = false;
};

struct UpdateSettings {
  double dt = 0.0;
  double alpha = 0.0;      // new = alpha U0 + (1 - alpha) (U + dt L(U))
  double dry_depth = 1e-10;
  double friction = 0.0;   // g n²
};

struct UpdateResult {
  bool any_negative;    // some new area < 0 (positivity lost, or round-off)
  bool any_non_finite;  // some new A or Q is NaN or infinite
  bool any_lateral;     // some q_l != 0 (then lateral_volume_rate() is worth computing)
};

// x^(-1/3) for x > 0 in loops that must vectorise (std::cbrt has no vector version and costs a
// library call): a bit-level first guess on the float representation (|relative error| < 3.5%),
// then three Newton steps y ← y (4 − x y³) / 3 for f(y) = y⁻³ − x, which roughly square the error
// each time (3.5e-2 → 2.5e-3 → 1.2e-5 → 3e-10) and need no division — far below the uncertainty
// of any Manning coefficient. x is clamped to [1e-30, 1e30].
inline double inverse_cube_root_positive(double x) {
  x = std::min(std::max(x, 1e-30), 1e30);
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(static_cast<float>(x));
  double y = static_cast<double>(std::bit_cast<float>(0x54a21d2au - bits / 3u));
  for (int k = 0; k < 3; ++k) y *= (4.0 - x * y * y * y) * (1.0 / 3.0);
  return y;
}

// Generalised minmod slope of a_{i-1}, a_i, a_{i+1} (θ in [1, 2]).
inline double limited_slope(double am, double a0, double ap, double theta) {
  const double d1 = theta * (a0 - am), d2 = theta * (ap - a0), dc = 0.5 * (ap - am);
  const double lo = std::min(std::min(d1, d2), dc), hi = std::max(std::max(d1, d2), dc);
  return d1 > 0.0 && d2 > 0.0 ? lo : (d1 < 0.0 && d2 < 0.0 ? hi : 0.0);
}

// van Leer's (1974) harmonic limiter: 2 d₋ d₊ / (d₋ + d₊) where the one-sided differences d± have
// the same sign, else 0. It lies between 0 and 2 min(|d₋|, |d₊|) (so h ± σ/2 >= 0, as for θ <= 2
// minmod), equals the central difference for linear data, and — unlike minmod, which switches
// between d₋ and d₊ — is differentiable wherever d₋ d₊ > 0, which lets time marching converge to
// steady states at Courant numbers where minmod's switching sustains a limit cycle.
inline double van_leer_slope(double am, double a0, double ap) {
  const double d1 = a0 - am, d2 = ap - a0;
  const double product = d1 * d2;
  const double sum = product > 0.0 ? d1 + d2 : 1.0;  // divide unconditionally, select after
  return product > 0.0 ? 2.0 * product / sum : 0.0;
}

// The slope of the linearisation at a limiter's kink (StageSettings::centred_kinks): the limited
// slope where it is clearly differentiable, the centred one elsewhere. van Leer's limiter has its
// kink where d₋d₊ <= 0; the generalised minmod also where its two smallest candidates θd₋, θd₊,
// (d₋ + d₊)/2 meet (e.g. d₋ = d₊ on a linear profile, where it switches between them).
inline double slope_centred_at_kinks(double am, double a0, double ap, double tolerance, bool van_leer,
                                     double theta) {
  const double d1 = a0 - am, d2 = ap - a0, centred = 0.5 * (ap - am);
  if (!(d1 * d2 > tolerance * tolerance)) return centred;
  if (van_leer) return van_leer_slope(am, a0, ap);
  double c[3] = {std::abs(theta * d1), std::abs(theta * d2), std::abs(centred)};
  std::sort(c, c + 3);
  return c[1] - c[0] > tolerance ? limited_slope(am, a0, ap, theta) : centred;
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

// Steps (1)–(3) on one reach: returns the largest wave speed over its interior faces. The end
// faces (0 and cells) are left for the caller.
double compute_interior_fluxes(Reach& reach, const StageSettings& settings, double gravity);
// Step (4) on one reach, from the fluxes of the last compute_interior_fluxes and the end faces.
UpdateResult apply_stage_update(Reach& reach, const UpdateSettings& settings, double gravity);
// Σ q_l,eff dx [m³/s] applied by the last stage (q_l of dry cells limited to inflow).
double lateral_volume_rate(const Reach& reach, double dry_depth);

}  // namespace canalsim::solver
