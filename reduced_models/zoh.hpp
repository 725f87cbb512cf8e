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

// The held, delayed input of interval k: `early` over its first f·h, `late` after.
struct HeldInterval {
  double early = 0.0, late = 0.0;
};

// Splits a delay of `delay_samples` (≥ 0) into d whole samples and the fraction f, and gives the
// held input of every interval from the (undelayed) sequence u: late = u_{k−d}, early =
// u_{k−d−1} (zero before the start).
std::vector<HeldInterval> held_delayed_input(const std::vector<double>& u, double delay_samples);
double delay_fraction(double delay_samples);

// Gain g_k of interval k given the model's deviation x_k at its start (called once per sample,
// in order, the last one included).
using IntervalGain = std::function<double(std::size_t k, double x_k)>;

// x_0 … x_{n−1} of T ẋ + x = g u(t − L) under the held input `held` (size n).
void solve_zoh_lag(const std::vector<HeldInterval>& held, double T, double h, double f,
                   const IntervalGain& gain, double* x);

// x_0 … x_{n−1} of Δy = K / ((T s + 1)(T2 s + 1)) applied to the held input (unit gain; K is
// applied by the caller).
void solve_zoh_two_lags(const std::vector<HeldInterval>& held, double T, double T2, double h,
                        double f, double* x);

// For a first-order lag simulated by solve_zoh_lag: the response to a delay of (d + f) samples
// is (1 − w) y^{(d)} + w y^{(d+1)}, where y^{(d)} is the response delayed by d whole samples
// and w = (a_f − a)/(1 − a) (→ f as h/T → 0). Lets a fitter re-delay one cached response.
double zoh_delay_weight(double T, double h, double f);

}  // namespace canalsim::reduced
