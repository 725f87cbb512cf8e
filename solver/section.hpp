// Prismatic cross-sections: trapezoid of bottom width b [m] and side slope m [horizontal per
// vertical]; m = 0 is a rectangle. Everything the scheme needs is a closed-form function of the
// depth h [m]:
//
//   A(h)  = h (b + m h)                       wetted area
//   T(h)  = b + 2 m h                         top width
//   P(h)  = b + 2 h sqrt(1 + m^2)             wetted perimeter
//   I1(h) = ∫_0^h (h - s) T(s) ds = b h^2/2 + m h^3/3   first moment of area about the surface
//   c(h)  = sqrt(g A / T)                     celerity of small waves
//   h(A)  = 2 A / (b + sqrt(b^2 + 4 m A))     inverse of A(h), written without cancellation
//
// The hydrostatic pressure force on a section is g I1 (Cunge, Holly & Verwey 1980, ch. 2); for a
// prismatic channel dI1/dh = A, which is what makes the hydrostatic reconstruction exact at rest.
#pragma once

#include <algorithm>
#include <cmath>

namespace canalsim::solver {

struct Section {
  double bottom_width = 1.0;  // b [m], >= 0; b + m > 0
  double side_slope = 0.0;    // m [-], >= 0 (0: rectangular)

  bool is_rectangular() const { return side_slope == 0.0; }
  double area(double h) const { return h * (bottom_width + side_slope * h); }
  double top_width(double h) const { return bottom_width + 2.0 * side_slope * h; }
  double wetted_perimeter(double h) const {
    return bottom_width + 2.0 * h * std::sqrt(1.0 + side_slope * side_slope);
  }
  double pressure_integral(double h) const {  // I1(h)
    return h * h * (0.5 * bottom_width + side_slope * h / 3.0);
  }
  double depth(double area_m2) const {
    // The floor keeps A = 0 in a triangle (b = 0) at h = 0 instead of 0/0.
    return 2.0 * area_m2 /
           std::max(bottom_width + std::sqrt(bottom_width * bottom_width + 4.0 * side_slope * area_m2), 1e-300);
  }
  double celerity(double h, double gravity) const {
    const double t = top_width(h);
    return t > 0.0 ? std::sqrt(gravity * area(h) / t) : 0.0;
  }
  // Mean of A over depths between h1 and h2: (I1(h2) - I1(h1)) / (h2 - h1), in closed form so it
  // is also defined for h1 == h2. Used for the well-balanced centred source term.
  double mean_area(double h1, double h2) const {
    return 0.5 * bottom_width * (h1 + h2) + side_slope * (h1 * h1 + h1 * h2 + h2 * h2) / 3.0;
  }
  // Critical depth for discharge Q: Q^2 T = g A^3 (Froude number 1); bisection for m > 0.
  double critical_depth(double discharge, double gravity) const;
  // Phi(h) = ∫_0^h sqrt(g T(s) / A(s)) ds: the depth part of the Riemann invariants u ± Phi(h).
  // For a rectangle Phi = 2 sqrt(g h) = 2c. Evaluated by Gauss–Legendre quadrature after the
  // substitution s = h τ^2, which removes the 1/sqrt(s) singularity at the bed.
  double characteristic_integral(double h, double gravity) const;
};

}  // namespace canalsim::solver
