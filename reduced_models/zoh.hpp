// Exact zero-order-hold (ZOH) simulation of the integer-order lags (LIOM, SOPD, NLIOM-F/S, and
// the fractional models at λ = 1).
//
// The recorded command u_k is held by the gate from t_k to t_{k+1}; delayed by L = (d + f) h
// (d whole samples, 0 ≤ f < 1) it holds u_{k−d−1} over the first f·h of the interval [t_k,
// t_{k+1}] and u_{k−d} over the rest. Integrating T ẋ + x = g u(t − L) exactly over the
// interval (the modified z-transform of the lag, e.g. Åström & Wittenmark, Computer-Controlled
// Systems, §2.3) gives, with a = e^{−h/T} and a_f = e^{−(1−f) h/T},
//
//     x_{k+1} = a x_k + g_k [ (1 − a_f) u_{k−d} + (a_f − a) u_{k−d−1} ],   x_0 = 0,
//
// which is the continuous lag's response sampled at t_k, whatever h/T: a fit at coarse sampling
// is not biased by the discretisation (backward Euler's T is h/2 too slow and its output one
// sample early). T = 0 gives a = a_f = 0: the held input itself. The gain g_k (K, or the
// nonlinear models' K·(head/H)^γ) is taken at the start of the interval, where the submerged
// models read their own level x_k.
//
// Two lags in series (SOPD) are integrated the same way with the 2×2 transition matrix of the
// cascade, in closed form.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

namespace canalsim::reduced {

// The command deviation u (one value per sample, undelayed) delayed by `delay_samples` = d + f
// (≥ 0) and held: over interval k it is early(k) = u_{k−d−1} for the first f·h, late(k) = u_{k−d}
// after (zero before the start).
class DelayedHold {
 public:
  DelayedHold(const std::vector<double>& u, double delay_samples);
  std::size_t size() const { return u_.size(); }
  double fraction() const { return f_; }
  double late(std::size_t k) const { return at(static_cast<std::ptrdiff_t>(k) - d_); }
  double early(std::size_t k) const { return at(static_cast<std::ptrdiff_t>(k) - d_ - 1); }

 private:
  double at(std::ptrdiff_t i) const {
    return i >= 0 && i < static_cast<std::ptrdiff_t>(u_.size()) ? u_[static_cast<std::size_t>(i)] : 0.0;
  }
  const std::vector<double>& u_;
  std::ptrdiff_t d_ = 0;
  double f_ = 0.0;
};

// Gain g_k of interval k given the model's deviation x_k at its start (called once per sample,
// in order, the last one included).
using IntervalGain = std::function<double(std::size_t k, double x_k)>;

// x_0 … x_{n−1} of T ẋ + x = g u(t − L) under the held input (n = input.size()); `gain` null:
// g = 1 (a linear model scales the result by K).
void solve_zoh_lag(const DelayedHold& input, double T, double h, const IntervalGain* gain, double* x);

// x_0 … x_{n−1} of Δy = 1 / ((T s + 1)(T2 s + 1)) applied to the held input (unit gain).
void solve_zoh_two_lags(const DelayedHold& input, double T, double T2, double h, double* x);

// For a first-order lag simulated by solve_zoh_lag: the response to a delay of (d + f) samples
// is (1 − w) y^{(d)} + w y^{(d+1)}, where y^{(d)} is the response delayed by d whole samples
// and w = (a_f − a)/(1 − a) (→ f as h/T → 0). Lets a fitter re-delay one cached response.
double zoh_delay_weight(double T, double h, double f);

}  // namespace canalsim::reduced
