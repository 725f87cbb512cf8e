#include "solver/section.hpp"

#include <algorithm>
#include <array>

namespace canalsim::solver {

double Section::critical_depth(double discharge, double gravity) const {
  const double q = std::abs(discharge);
  if (q == 0.0) return 0.0;
  if (is_rectangular()) return std::cbrt(q * q / (gravity * bottom_width * bottom_width));
  // Froude^2 = Q^2 T / (g A^3) decreases monotonically with h: bracket, then bisect.
  auto froude2 = [&](double h) {
    const double a = area(h);
    return q * q * top_width(h) / (gravity * a * a * a);
  };
  double lo = 0.0, hi = 1.0;
  while (froude2(hi) > 1.0 && hi < 1e6) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (froude2(mid) > 1.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double Section::characteristic_integral(double h, double gravity) const {
  if (h <= 0.0) return 0.0;
  if (is_rectangular()) return 2.0 * std::sqrt(gravity * h);
  // 8-point Gauss–Legendre nodes/weights on [-1, 1], mapped to τ in [0, 1]; the integrand
  // 2 h τ sqrt(g T(hτ²)/A(hτ²)) is smooth in τ: A(s)/τ² = h (b + m s) stays finite.
  static constexpr std::array<double, 8> x = {-0.9602898564975363, -0.7966664774136267,
                                              -0.5255324099163290, -0.1834346424956498,
                                              0.1834346424956498,  0.5255324099163290,
                                              0.7966664774136267,  0.9602898564975363};
  static constexpr std::array<double, 8> w = {0.1012285362903763, 0.2223810344533745,
                                              0.3137066458778873, 0.3626837833783620,
                                              0.3626837833783620, 0.3137066458778873,
                                              0.2223810344533745, 0.1012285362903763};
  // Composite rule on τ-panels that are finer near the bed, where T/A changes fastest for a wide
  // trapezoid with a narrow bottom (the transition at s ~ b/m).
  static constexpr std::array<double, 5> edges = {0.0, 0.125, 0.3, 0.6, 1.0};
  double sum = 0.0;
  for (std::size_t p = 0; p + 1 < edges.size(); ++p) {
    const double lo = edges[p], half = 0.5 * (edges[p + 1] - edges[p]);
    for (std::size_t k = 0; k < x.size(); ++k) {
      const double tau = lo + half * (x[k] + 1.0);
      const double s = h * tau * tau;
      // sqrt(T/A) · 2hτ = 2h sqrt(T / (A/τ²)), and A(s)/τ² = h (b + m s) is finite at τ = 0.
      const double integrand =
          2.0 * h * std::sqrt(gravity * top_width(s) / (h * (bottom_width + side_slope * s)));
      sum += half * w[k] * integrand;
    }
  }
  return sum;
}

}  // namespace canalsim::solver
