#include "diagnosis/residual_tests.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace canalsim::diagnosis {
namespace {

std::vector<double> centred(const std::vector<double>& x) {
  const double mean = x.empty() ? 0.0 : std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  std::vector<double> out(x.size());
  std::transform(x.begin(), x.end(), out.begin(), [mean](double v) { return v - mean; });
  return out;
}

double sum_squares(const std::vector<double>& x) {
  return std::inner_product(x.begin(), x.end(), x.begin(), 0.0);
}

void count_outside(CorrelationTest& test, double level, double p) {
  test.outside = static_cast<int>(std::count_if(test.values.begin(), test.values.end(),
                                                [&](double v) { return std::abs(v) > test.bound; }));
  test.allowed = binomial_allowance(static_cast<int>(test.values.size()), p, level);
  test.pass = test.outside <= test.allowed;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

Status ResidualTestOptions::validate() const {
  Validator check;
  check.require(max_lag >= 1 && max_lag <= 1000, "max_lag", max_lag, "1..1000");
  check.require(z > 0.0 && z <= 10.0, "z", z, "(0, 10]");
  check.require(family_level > 0.0 && family_level < 1.0, "family_level", family_level, "(0, 1)");
  return check.status();
}

std::vector<double> cross_correlation(const std::vector<double>& u, const std::vector<double>& e,
                                      int max_lag) {
  if (u.size() != e.size()) throw std::invalid_argument("cross_correlation: input and residual lengths differ");
  const std::vector<double> a = centred(u), b = centred(e);
  const double norm = std::sqrt(sum_squares(a) * sum_squares(b));
  std::vector<double> r(2 * static_cast<std::size_t>(std::max(max_lag, 0)) + 1, 0.0);
  if (norm <= 0.0) return r;
  const auto n = static_cast<long>(a.size());
  for (long k = -max_lag; k <= max_lag; ++k) {
    double s = 0.0;
    for (long t = std::max(0L, k); t < n && t - k < n; ++t) s += a[static_cast<std::size_t>(t - k)] * b[static_cast<std::size_t>(t)];
    r[static_cast<std::size_t>(k + max_lag)] = s / norm;
  }
  return r;
}

int binomial_allowance(int n, double p, double level) {
  // Walk up the binomial pmf until the upper tail is below `level`.
  double pmf = std::pow(1.0 - p, n), cdf = pmf;
  int a = 0;
  while (1.0 - cdf > level && a < n) {
    pmf *= (static_cast<double>(n - a) / static_cast<double>(a + 1)) * (p / (1.0 - p));
    ++a;
    cdf += pmf;
  }
  return a;
}

ResidualTests residual_tests(const std::vector<double>& residual, const std::vector<double>& input,
                             const ResidualTestOptions& options) {
  if (const Status status = options.validate(); !status) {
    throw std::invalid_argument("residual test options: " + status.message());
  }
  if (!input.empty() && input.size() != residual.size()) {
    throw std::invalid_argument("residual_tests: input and residual lengths differ");
  }
  const double n = static_cast<double>(std::max<std::size_t>(residual.size(), 1));
  // Two-sided probability of a white value falling outside ±z/sqrt(N).
  const double p_out = std::erfc(options.z / std::sqrt(2.0));
  ResidualTests out;
  const std::vector<double> r = autocorrelation(residual, options.max_lag);
  out.autocorrelation.bound = options.z / std::sqrt(n);
  for (int k = 1; k <= options.max_lag; ++k) {
    out.autocorrelation.lags.push_back(k);
    out.autocorrelation.values.push_back(r[static_cast<std::size_t>(k)]);
  }
  count_outside(out.autocorrelation, options.family_level, p_out);
  if (!input.empty()) {
    out.cross_correlation.values = cross_correlation(input, residual, options.max_lag);
    for (int k = -options.max_lag; k <= options.max_lag; ++k) out.cross_correlation.lags.push_back(k);
    out.cross_correlation.bound = out.autocorrelation.bound;
    count_outside(out.cross_correlation, options.family_level, p_out);
  }
  return out;
}

double noise_level(const std::vector<double>& y, double resolution) {
  std::vector<double> d2;
  for (std::size_t k = 2; k < y.size(); ++k) d2.push_back(std::abs(y[k] - 2.0 * y[k - 1] + y[k - 2]));
  // MAD of a second difference of white noise: Var = 6 sigma^2; 1.4826 makes the MAD consistent.
  const double sigma = 1.4826 * median(d2) / std::sqrt(6.0);
  return std::max(sigma, resolution / std::sqrt(12.0));
}

double effective_samples(const std::vector<double>& e, int max_lag) {
  const std::vector<double> r = autocorrelation(e, max_lag);
  double sum = 0.0;
  for (std::size_t k = 1; k < r.size(); ++k) {
    if (r[k] < 0.05) break;
    sum += r[k];
  }
  return std::max(1.0, static_cast<double>(e.size()) / (1.0 + 2.0 * sum));
}

}  // namespace canalsim::diagnosis
