// Residual tests against closed-form expectations: white noise passes, an AR(1) sequence fails
// with r(k) ≈ a^k, an input leaking into the residual shows at its lag.
#include "diagnosis/residual_tests.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "testing/signals.hpp"

namespace canalsim::diagnosis {
namespace {

using testing::white_noise;

std::vector<double> ar1(std::size_t n, double a, std::uint64_t seed) {
  std::vector<double> e = white_noise(n, seed), x(n);
  x[0] = e[0];
  for (std::size_t t = 1; t < n; ++t) x[t] = a * x[t - 1] + e[t];
  return x;
}

TEST(ResidualTests, WhiteNoisePassesBothTestsInMostRealisations) {
  int passed = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const auto e = white_noise(2000, seed), u = white_noise(2000, seed + 1000);
    const ResidualTests t = residual_tests(e, u);
    passed += t.white() && t.uncorrelated();
  }
  // Each test is built to fail at most 5% of the time on white data; both together at most ~10%.
  EXPECT_GE(passed, 16);
}

TEST(ResidualTests, AutocorrelationOfAr1IsAPowerOfItsCoefficient) {
  const double a = 0.8;
  const auto x = ar1(20000, a, 3);
  const std::vector<double> r = autocorrelation(x, 5);
  EXPECT_DOUBLE_EQ(r[0], 1.0);
  for (int k = 1; k <= 5; ++k) EXPECT_NEAR(r[static_cast<std::size_t>(k)], std::pow(a, k), 0.03) << "lag " << k;
  EXPECT_FALSE(residual_tests(x, {}).white());
}

TEST(ResidualTests, BoundIsZOverSqrtN) {
  const ResidualTests t = residual_tests(white_noise(2500, 4), {});
  EXPECT_NEAR(t.autocorrelation.bound, 2.58 / 50.0, 1e-12);
  EXPECT_EQ(t.autocorrelation.lags.size(), 25u);
  EXPECT_TRUE(t.cross_correlation.values.empty());
}

TEST(ResidualTests, InputLeakingIntoTheResidualShowsAtItsLag) {
  const auto u = white_noise(5000, 5), v = white_noise(5000, 6);
  std::vector<double> e(u.size());
  for (std::size_t t = 0; t < u.size(); ++t) e[t] = v[t] + (t >= 3 ? 0.5 * u[t - 3] : 0.0);
  const ResidualTests t = residual_tests(e, u);
  EXPECT_FALSE(t.uncorrelated());
  // r_ue(3) = 0.5 / sqrt(1 + 0.25) for unit variances.
  const auto& c = t.cross_correlation;
  EXPECT_NEAR(c.values[static_cast<std::size_t>(3 + 25)], 0.5 / std::sqrt(1.25), 0.03);
  EXPECT_EQ(c.lags[static_cast<std::size_t>(3 + 25)], 3);
}

TEST(ResidualTests, BinomialAllowanceMatchesHandComputedTails) {
  // n = 25, p = 0.01: P(X > 0) = 0.222, P(X > 1) = 0.026 -> allowance 1 at the 5% level.
  EXPECT_EQ(binomial_allowance(25, 0.01, 0.05), 1);
  EXPECT_EQ(binomial_allowance(10, 0.0, 0.05), 0);
}

TEST(ResidualTests, NoiseLevelOfASmoothSignalPlusWhiteNoiseIsTheNoise) {
  const auto n = white_noise(5000, 7, 0.2);
  std::vector<double> y(n.size());
  for (std::size_t k = 0; k < y.size(); ++k) y[k] = 5.0 * std::sin(0.01 * static_cast<double>(k)) + n[k];
  EXPECT_NEAR(noise_level(y, 0.0), 0.2, 0.02);
  // Never below the quantisation floor r / sqrt(12).
  EXPECT_NEAR(noise_level(std::vector<double>(100, 1.0), 0.6), 0.6 / std::sqrt(12.0), 1e-12);
}

TEST(ResidualTests, EffectiveSamplesOfAr1FollowTheBartlettFactor) {
  const double a = 0.5;
  const auto x = ar1(40000, a, 8);
  // N (1 - a) / (1 + a) for a geometric autocorrelation, truncated where r < 0.05 (a^5 = 0.03).
  EXPECT_NEAR(effective_samples(x) / 40000.0, (1.0 - a) / (1.0 + a), 0.05);
}

TEST(ResidualTests, InvalidOptionsAreNamed) {
  ResidualTestOptions o;
  o.max_lag = 0;
  EXPECT_NE(o.validate().message().find("max_lag"), std::string::npos);
  EXPECT_THROW(residual_tests({1.0, 2.0}, {}, o), std::invalid_argument);
  EXPECT_THROW(residual_tests({1.0, 2.0}, {1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace canalsim::diagnosis
