// Residual tests of a model against a recording, as MATLAB's `resid`: the autocorrelation of the
// residual e (is it white?) and its cross-correlation with the input u (is anything of u left
// in e?), each with the 99% band of a white sequence, ±z/sqrt(N) with z = 2.58.
//
// Normalised estimates (biased, divided by N, as in Ljung's System Identification, 2nd ed.,
// Section 16.6):
//   r_e(k)  = Σ_t ẽ(t) ẽ(t+k) / Σ_t ẽ(t)²,                 k = 1..M
//   r_ue(k) = Σ_t ũ(t-k) ẽ(t) / sqrt(Σ ũ² Σ ẽ²),           k = -M..M (k > 0: u leads e)
// with ẽ, ũ the mean-removed series. Under whiteness each value is ~N(0, 1/N); a test passes when
// the number of lags outside the band is no more than the binomial count that a white sequence
// exceeds with probability 5% (so "one lag of 25 outside" is not a failure).
#pragma once

#include "core/statistics.hpp"

#include "core/status.hpp"

#include <string>
#include <vector>

namespace canalsim::diagnosis {

struct ResidualTestOptions {
  int max_lag = 25;          // M, lags tested (MATLAB's default 25); range [1, 1000]
  double z = 2.58;           // band half-width in standard deviations (99%); range (0, 10]
  double family_level = 0.05;  // allowed probability of a false "not white" over all lags; (0, 1)
  // Empty when valid; otherwise one line naming the field and its range.
  Status validate() const;
};

struct CorrelationTest {
  std::vector<int> lags;
  std::vector<double> values;  // normalised correlation at each lag
  double bound = 0.0;          // z / sqrt(N)
  int outside = 0;             // lags with |value| > bound
  int allowed = 0;             // binomial allowance (see above)
  bool pass = true;
};

struct ResidualTests {
  CorrelationTest autocorrelation;    // lags 1..M
  CorrelationTest cross_correlation;  // lags -M..M; empty when no input was given
  bool white() const { return autocorrelation.pass; }
  bool uncorrelated() const { return cross_correlation.pass; }
};

// r_e(k) for k = 0..max_lag (r_e(0) = 1; all zero for a constant series): core's, which the
// report's autocorrelation plots use too.
using canalsim::autocorrelation;
// r_ue(k) for k = -max_lag..max_lag (index k + max_lag). Lengths must match.
std::vector<double> cross_correlation(const std::vector<double>& u, const std::vector<double>& e,
                                      int max_lag);
// The smallest count a such that P(Binomial(n, p) > a) <= level.
int binomial_allowance(int n, double p, double level);

// Both tests; `input` may be empty (then only whiteness). Throws std::invalid_argument on bad
// options or mismatched lengths.
ResidualTests residual_tests(const std::vector<double>& residual, const std::vector<double>& input,
                             const ResidualTestOptions& options = {});

// Robust standard deviation of the white measurement noise in a sampled signal: from the median
// absolute second difference (a smooth signal's curvature is small between samples), and never
// below the quantisation floor r/sqrt(12).
double noise_level(const std::vector<double>& y, double resolution);

// Effective number of independent samples of a correlated residual: N / (1 + 2 Σ r_e(k)) over the
// lags until r_e first drops below 0.05; at least 1.
double effective_samples(const std::vector<double>& e, int max_lag = 200);

}  // namespace canalsim::diagnosis
