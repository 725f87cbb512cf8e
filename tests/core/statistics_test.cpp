// core/statistics.hpp on cases solved by hand: the integrated autocorrelation time of white noise
// (1) and of an AR(1) series (τ = (1 + φ) / (1 − φ)); the covariance of a mean (σ² / N) and of a
// straight-line fit on white noise (the ordinary least-squares one); an exact trade-off is
// undetermined (+∞, NaN correlations).
#include "core/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "testing/signals.hpp"

namespace canalsim {
namespace {

std::vector<double> ar1(double phi, std::size_t n, unsigned seed) { return testing::ar1_noise(phi, n, seed); }

TEST(Statistics, IntegratedAutocorrelationTimeOfWhiteNoiseAndAnAr1Series) {
  EXPECT_NEAR(integrated_autocorrelation_time(ar1(0.0, 100000, 1)), 1.0, 0.05);
  EXPECT_NEAR(integrated_autocorrelation_time(ar1(0.5, 100000, 2)), 3.0, 0.15);
  EXPECT_EQ(integrated_autocorrelation_time({1.0, 2.0}), 1.0);
  EXPECT_NEAR(autocorrelation_inflation({ar1(0.5, 100000, 3)}), 3.0, 0.15);
}

// y = a + b x + e on white noise: the covariance is the OLS one, s² (XᵀX)⁻¹, within the sandwich's
// sampling error (a few per cent on 20 000 samples).
TEST(Statistics, AStraightLineOnWhiteNoiseHasTheOrdinaryLeastSquaresCovariance) {
  const std::size_t n = 20000;
  const std::vector<double> e = ar1(0.0, n, 4);
  std::vector<double> J(2 * n);
  double sx = 0.0, sxx = 0.0, sse = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double x = static_cast<double>(k) / static_cast<double>(n);
    J[2 * k] = 1.0;
    J[2 * k + 1] = x;
    sx += x;
    sxx += x * x;
    sse += e[k] * e[k];
  }
  // e is not exactly orthogonal to the columns; the OLS formula holds for the residuals of the
  // fit, which differ from e by O(1/sqrt(n)) — negligible at this tolerance.
  const double s2 = sse / static_cast<double>(n - 2), det = static_cast<double>(n) * sxx - sx * sx;
  const LeastSquaresCovariance c = least_squares_covariance(J, 2, e, {e});
  const std::vector<double> std = standard_deviations(c);
  EXPECT_NEAR(std[0], std::sqrt(s2 * sxx / det), 0.05 * std::sqrt(s2 * sxx / det));
  EXPECT_NEAR(std[1], std::sqrt(s2 * static_cast<double>(n) / det), 0.05 * std::sqrt(s2 * static_cast<double>(n) / det));
  const auto rho = correlations(c);
  EXPECT_NEAR(rho[0][1], -sx / std::sqrt(static_cast<double>(n) * sxx), 0.02);
  EXPECT_GE(c.inflation, 1.0);
  EXPECT_LT(c.inflation, 1.1);
}

TEST(Statistics, AnExactTradeOffIsUndetermined) {
  const std::vector<double> e = ar1(0.0, 1000, 5);
  std::vector<double> J(2 * e.size());
  for (std::size_t k = 0; k < e.size(); ++k) J[2 * k] = J[2 * k + 1] = std::sin(0.1 * static_cast<double>(k));
  const LeastSquaresCovariance c = least_squares_covariance(J, 2, e, {e});
  ASSERT_EQ(c.null_directions.size(), 1u);
  EXPECT_TRUE(std::isinf(standard_deviations(c)[0]));
  EXPECT_TRUE(std::isnan(correlations(c)[0][1]));
}

}  // namespace
}  // namespace canalsim
