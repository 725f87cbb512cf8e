// Tests of reduced_models/gl.*: the Grünwald–Letnikov simulation of T D^λ x + x = f.
#include "reduced_models/gl.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <random>
#include <numbers>

namespace canalsim::reduced {
namespace {

// Mittag-Leffler E_α(−s^α), 0 < α < 1, evaluated independently of the GL scheme:
//  * power series Σ (−s^α)^k / Γ(αk + 1) in long double for small s (terms grow like e^s, so
//    the cancellation costs about s/ln 10 digits of long double's 19);
//  * for larger s the integral representation (Podlubny 1999, eq. 1.133 specialised; Gorenflo &
//    Mainardi) E_α(−s^α) = sin(απ)/π ∫_0^∞ e^{−rs} r^{α−1} / (r^{2α} + 2 r^α cos(απ) + 1) dr,
//    integrated by the trapezoid rule after r = e^v (exponentially convergent for this smooth,
//    rapidly decaying integrand).
long double ml_series(double alpha, double s) {
  const long double x = std::pow(static_cast<long double>(s), static_cast<long double>(alpha));
  long double sum = 0.0L;
  for (int k = 0; k < 2000; ++k) {
    const long double log_term = k * std::log(x) - std::lgamma(static_cast<long double>(alpha) * k + 1.0L);
    const long double term = (k % 2 ? -1.0L : 1.0L) * std::exp(log_term);
    sum += term;
    if (k > 10 && std::fabs(term) < 1e-22L) break;
  }
  return sum;
}

double ml_integral(double alpha, double s) {
  const double pi = std::numbers::pi;
  const double dv = 0.005;
  double sum = 0.0;
  for (double v = -120.0; v < 8.0; v += dv) {
    const double r = std::exp(v);
    const double ra = std::pow(r, alpha);
    sum += std::exp(-r * s) * ra / (ra * ra + 2.0 * ra * std::cos(alpha * pi) + 1.0);
  }
  return std::sin(alpha * pi) / pi * sum * dv;
}

std::string scientific(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3e", v);
  return buffer;
}

double mittag_leffler_neg(double alpha, double s) {
  if (s == 0.0) return 1.0;
  return s < 6.0 ? static_cast<double>(ml_series(alpha, s)) : ml_integral(alpha, s);
}

TEST(MittagLefflerReference, SeriesAndIntegralAgreeWhereBothAreAccurate) {
  for (double alpha : {0.5, 0.7, 0.9}) {
    for (double s : {0.5, 2.0, 5.0}) {
      EXPECT_NEAR(static_cast<double>(ml_series(alpha, s)), ml_integral(alpha, s), 1e-9)
          << "alpha " << alpha << " s " << s;
    }
  }
  // α = 1/2 has the closed form E_{1/2}(−z) = e^{z²} erfc(z).
  for (double z : {0.3, 1.0, 2.5}) {
    const double s = z * z;
    EXPECT_NEAR(mittag_leffler_neg(0.5, s), std::exp(z * z) * std::erfc(z), 1e-12);
  }
  EXPECT_NEAR(mittag_leffler_neg(0.5, 49.0), std::exp(49.0) * std::erfc(7.0), 1e-9);
}

TEST(GlWeights, FollowTheGeneralisedBinomialCoefficients) {
  const double l = 0.6;
  const auto w = gl_weights(l, 4);
  EXPECT_DOUBLE_EQ(w[0], 1.0);
  EXPECT_DOUBLE_EQ(w[1], -l);
  EXPECT_NEAR(w[2], l * (l - 1.0) / 2.0, 1e-15);
  EXPECT_NEAR(w[3], -l * (l - 1.0) * (l - 2.0) / 6.0, 1e-15);
  const auto w1 = gl_weights(1.0, 5);
  EXPECT_EQ(w1, (std::vector<double>{1.0, -1.0, 0.0, 0.0, 0.0}));
}

TEST(GlOrderOne, IsExactlyBackwardEulerForEveryMemoryChoice) {
  const double T = 2.0, h = 0.13;
  const std::size_t n = 400;
  std::vector<double> f(n, 1.0);
  for (auto memory : {GlMemory::short_memory, GlMemory::full, GlMemory::full_direct}) {
    const auto x = solve_fractional_lag(f, T, 1.0, h, {memory, 500});
    for (std::size_t k = 0; k < n; ++k) {
      // Backward Euler T (x_k − x_{k−1})/h + x_k = 1, x_{−1} = 0, solved in closed form.
      const double exact = 1.0 - std::pow(T / (T + h), static_cast<double>(k + 1));
      ASSERT_NEAR(x[k], exact, 1e-13) << "k " << k;
    }
  }
}

TEST(GlOrderOne, ReproducesTheBackwardEulerRecursionForAnArbitraryInput) {
  const double T = 0.7, h = 0.13;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  std::vector<double> f(1000);
  for (double& v : f) v = dist(rng);
  const auto x = solve_fractional_lag(f, T, 1.0, h);
  double prev = 0.0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double expected = (T / h * prev + f[k]) / (1.0 + T / h);
    ASSERT_NEAR(x[k], expected, 1e-13);
    prev = expected;
  }
}

TEST(GlFullMemory, StepResponseMatchesOneMinusMittagLefflerAtFineSteps) {
  const double T = 1.0, h = 1e-3;
  const std::size_t n = 5000;  // t up to 5 s
  for (double lambda : {0.5, 0.8}) {
    const std::vector<double> f(n, 1.0);
    const auto x = solve_fractional_lag(f, T, lambda, h, {GlMemory::full, 0});
    double worst = 0.0;
    for (std::size_t k = 99; k < n; k += 50) {
      const double t = static_cast<double>(k + 1) * h;  // sample k ends the (k+1)-th step
      const double s = t * std::pow(T, -1.0 / lambda);
      const double exact = 1.0 - mittag_leffler_neg(lambda, s);
      worst = std::max(worst, std::abs(x[k] - exact));
    }
    RecordProperty(lambda == 0.5 ? "worst_error_lambda_0_5" : "worst_error_lambda_0_8", scientific(worst));
    EXPECT_LT(worst, 1e-3) << "lambda " << lambda;
  }
}

TEST(GlShortMemory, SteadyStateShowsTheTruncationBias) {
  const double T = 1.5, lambda = 0.6, h = 0.13;
  const std::size_t N = 500;
  const std::vector<double> f(20000, 1.0);
  const auto x = solve_fractional_lag(f, T, lambda, h, {GlMemory::short_memory, N});
  const double discrete = short_memory_steady_state(T, lambda, h, N);
  EXPECT_NEAR(x.back(), discrete, 1e-9);
  // Asymptotic form of the bias: Σ_{j≤N} w_j ≈ N^−λ / Γ(1−λ).
  const double asymptotic = 1.0 / (1.0 + T * std::pow(N * h, -lambda) / std::tgamma(1.0 - lambda));
  EXPECT_NEAR(x.back(), asymptotic, 0.01 * (1.0 - asymptotic));
  RecordProperty("steady_state", std::to_string(x.back()));
  RecordProperty("asymptotic_bias_formula", std::to_string(asymptotic));
  EXPECT_LT(x.back(), 0.99);  // the bias is real: the true steady state is 1
}

TEST(GlFullMemory, FftDivideAndConquerEqualsDirectSummation) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  const std::size_t n = 3000;
  std::vector<double> f(n);
  for (double& v : f) v = dist(rng);
  for (double lambda : {0.35, 0.7, 1.3}) {
    const auto fast = solve_fractional_lag(f, 1.2, lambda, 0.13, {GlMemory::full, 0});
    const auto direct = solve_fractional_lag(f, 1.2, lambda, 0.13, {GlMemory::full_direct, 0});
    double worst = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      ASSERT_NEAR(fast[k], direct[k], 1e-10) << "k " << k;
      worst = std::max(worst, std::abs(fast[k] - direct[k]));
    }
    RecordProperty("max_difference_lambda_" + std::to_string(lambda), scientific(worst));
  }
}

TEST(GlFullMemory, OnlineForcingThatReadsThePastSolutionMatchesDirectSummation) {
  const std::size_t n = 2500;
  const OnlineForcing forcing = [](std::size_t k, const double* x) {
    const double past = k > 0 ? x[k - 1] : 0.0;
    return std::sin(0.01 * static_cast<double>(k)) * (1.0 + 0.5 * std::tanh(past));
  };
  std::vector<double> fast(n), direct(n);
  solve_fractional_lag(n, 0.8, 0.55, 0.13, {GlMemory::full, 0}, forcing, fast.data());
  solve_fractional_lag(n, 0.8, 0.55, 0.13, {GlMemory::full_direct, 0}, forcing, direct.data());
  for (std::size_t k = 0; k < n; ++k) ASSERT_NEAR(fast[k], direct[k], 1e-10);
}

TEST(GlShortMemory, EqualsFullMemoryWhileTheHistoryIsShorterThanN) {
  std::vector<double> f(400, 1.0);
  const auto s = solve_fractional_lag(f, 1.0, 0.5, 0.13, {GlMemory::short_memory, 500});
  const auto d = solve_fractional_lag(f, 1.0, 0.5, 0.13, {GlMemory::full_direct, 0});
  for (std::size_t k = 0; k < f.size(); ++k) ASSERT_NEAR(s[k], d[k], 1e-12);
}

TEST(GlArguments, RejectsNegativeTimeConstantZeroOrderAndEmptyMemory) {
  const std::vector<double> f(10, 1.0);
  EXPECT_THROW(solve_fractional_lag(f, -1.0, 0.5, 0.1), std::invalid_argument);
  EXPECT_THROW(solve_fractional_lag(f, 1.0, 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(solve_fractional_lag(f, 1.0, 0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(solve_fractional_lag(f, 1.0, 0.5, 0.1, {GlMemory::short_memory, 0}),
               std::invalid_argument);
  const GlOptions bad{GlMemory::short_memory, 0};
  EXPECT_NE(bad.validate().message().find("memory_terms"), std::string::npos);
}

TEST(GlZeroTimeConstant, PassesTheForcingThrough) {
  const std::vector<double> f{1.0, 2.0, -3.0};
  EXPECT_EQ(solve_fractional_lag(f, 0.0, 0.5, 0.1), f);
}

}  // namespace
}  // namespace canalsim::reduced
