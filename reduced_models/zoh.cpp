#include "reduced_models/zoh.hpp"

#include <algorithm>
#include <cmath>

namespace canalsim::reduced {
namespace {

// e^{−τ/T}, with T = 0 (no lag) giving 0 for every τ > 0.
double decay(double tau, double T) { return T > 0.0 ? std::exp(-tau / T) : 0.0; }

// (φ(T) − φ(T2)) / (T − T2), or φ'(T) where the two are too close for the difference.
template <class F, class D>
double divided_difference(F phi, D derivative, double T, double T2) {
  if (std::abs(T - T2) <= 1e-7 * std::max(T, T2)) return derivative(0.5 * (T + T2));
  return (phi(T) - phi(T2)) / (T - T2);
}

// Transition over τ of the cascade T ẋ1 + x1 = u, T2 ẋ2 + x2 = x1 (both T, T2 > 0) with u held:
// x(τ) = Φ x(0) + Ψ u, in closed form (Φ lower triangular).
struct CascadeStep {
  double p11, p21, p22, q1, q2;
  CascadeStep(double tau, double T, double T2) {
    p11 = decay(tau, T);
    p22 = decay(tau, T2);
    // Φ21 = T (e^{−τ/T} − e^{−τ/T2}) / (T − T2)
    p21 = T * divided_difference([&](double s) { return decay(tau, s); },
                                 [&](double s) { return decay(tau, s) * tau / (s * s); }, T, T2);
    q1 = 1.0 - p11;
    // Ψ2 = 1 − (T e^{−τ/T} − T2 e^{−τ/T2}) / (T − T2), the cascade's step response
    q2 = 1.0 - divided_difference([&](double s) { return s * decay(tau, s); },
                                  [&](double s) { return decay(tau, s) * (1.0 + tau / s); }, T, T2);
  }
  void apply(double& x1, double& x2, double u) const {
    const double y1 = p11 * x1 + q1 * u;
    x2 = p21 * x1 + p22 * x2 + q2 * u;
    x1 = y1;
  }
};

}  // namespace

DelayedHold::DelayedHold(const std::vector<double>& u, double delay_samples) : u_(u) {
  const double whole = std::floor(delay_samples);
  d_ = static_cast<std::ptrdiff_t>(whole);
  f_ = delay_samples - whole;
}

void solve_zoh_lag(const DelayedHold& input, double T, double h, const IntervalGain* gain, double* x) {
  const std::size_t n = input.size();
  if (n == 0) return;
  const double f = input.fraction();
  const double a = decay(h, T), a_f = decay((1.0 - f) * h, T);
  const double w_late = 1.0 - a_f, w_early = a_f - a;
  x[0] = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double g = gain ? (*gain)(k, x[k]) : 1.0;
    if (k + 1 == n) break;
    x[k + 1] = a * x[k] + g * (w_late * input.late(k) + w_early * input.early(k));
  }
}

void solve_zoh_two_lags(const DelayedHold& input, double T, double T2, double h, double* x) {
  if (T <= 0.0 || T2 <= 0.0) {  // one lag (or none): the lags commute
    solve_zoh_lag(input, std::max(T, T2), h, nullptr, x);
    return;
  }
  const std::size_t n = input.size();
  if (n == 0) return;
  // Over the early part (f h) the cascade is driven by `early`, then by `late`.
  const double f = input.fraction();
  const CascadeStep early_step(f * h, T, T2), late_step((1.0 - f) * h, T, T2);
  double x1 = 0.0, x2 = 0.0;
  x[0] = 0.0;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    if (f > 0.0) early_step.apply(x1, x2, input.early(k));
    late_step.apply(x1, x2, input.late(k));
    x[k + 1] = x2;
  }
}

double zoh_delay_weight(double T, double h, double f) {
  if (!(T > 0.0)) return 0.0;  // no lag: the sample sees the late input only
  const double a = std::exp(-h / T);
  if (1.0 - a < 1e-12) return f;  // h ≪ T: the limit
  return (std::exp(-(1.0 - f) * h / T) - a) / (1.0 - a);
}

}  // namespace canalsim::reduced
