// Grünwald–Letnikov (GL) simulation of the fractional first-order lag
//
//     T · D^λ x(t) + x(t) = f(t),     x(t) = 0 and f(t) = 0 for t ≤ 0,
//
// the dynamic core of every reduced model (paper eqs. 3, 6, 12–15; GL definition eq. A1–A2).
// On the grid t_k = k·h the GL derivative is D^λ x(t_k) ≈ h^−λ Σ_{j=0}^{M_k} w_j x_{k−j} with
// w_j = (−1)^j binom(λ, j), computed by the recursion w_0 = 1, w_j = w_{j−1} (1 − (λ+1)/j).
// Substituting gives the implicit-in-x_k (but linear) recursion
//
//     x_k = ( f_k − c · s_k ) / (1 + c),   c = T h^−λ,   s_k = Σ_{j=1}^{M_k} w_j x_{k−j}.
//
// Memory:
//  * short memory (paper, Appendix A): M_k = min(k, N) with N = 500 past samples (memory length
//    N·h). Cost O(n N). The truncation biases the steady state: a unit step settles at
//    1 / (1 + c Σ_{j=0}^{N} w_j) ≈ 1 / (1 + T (N h)^−λ / Γ(1−λ)).
//  * full memory: M_k = k. The history sums s_k form an online (relaxed) convolution, because
//    x_k needs s_k, which needs x_0..x_{k−1}. It is evaluated by divide and conquer: solve the
//    first half of a block, add its contribution to the second half's s with one FFT
//    convolution (Eigen's FFT, kissfft backend), recurse into the second half. Cost
//    O(n log² n); `full_direct` is the O(n²) reference sum used in tests.
// With λ = 1 the weights are (1, −1, 0, …): the scheme is exactly backward Euler.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "core/status.hpp"

namespace canalsim::reduced {

enum class GlMemory {
  short_memory,  // N past samples (the paper's choice, N = 500)
  full,          // all past samples, FFT-based divide and conquer, O(n log² n)
  full_direct,   // all past samples, direct O(n²) summation (reference)
};

struct GlOptions {
  GlMemory memory = GlMemory::short_memory;
  // N: number of past samples kept by the short-memory approximation (paper: 500).
  std::size_t memory_terms = 500;

  // Ok, or one line naming the offending field (core/status.hpp).
  [[nodiscard]] Status validate() const;
};

// The first `count` GL weights w_j = (−1)^j binom(λ, j), j = 0 … count−1 (eq. A2).
std::vector<double> gl_weights(double lambda, std::size_t count);

// Forcing evaluated online: f_k given the solution x_0 … x_{k−1} (pointer to x_0). Lets the
// nonlinear models make the input depend on the simulated output (eqs. 14–15).
using OnlineForcing = std::function<double(std::size_t k, const double* x)>;

// Solves T D^λ x + x = f on n samples of step h; writes x_0 … x_{n−1} to `x` (size n).
// Requires T ≥ 0, λ > 0, h > 0 (checked; std::invalid_argument otherwise).
void solve_fractional_lag(std::size_t n, double T, double lambda, double h, const GlOptions& options,
                          const OnlineForcing& forcing, double* x);

// Convenience form with a precomputed forcing sequence.
std::vector<double> solve_fractional_lag(const std::vector<double>& f, double T, double lambda,
                                         double h, const GlOptions& options = {});

// Steady state reached by a unit step under the short-memory approximation:
// 1 / (1 + T h^−λ Σ_{j=0}^{N} w_j) (exact for the discrete scheme).
double short_memory_steady_state(double T, double lambda, double h, std::size_t memory_terms);

}  // namespace canalsim::reduced
