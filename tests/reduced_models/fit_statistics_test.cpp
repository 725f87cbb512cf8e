// How sure a fit is (FitResult::std, correlation, inflation; reduced_models/fit_statistics.cpp),
// against truths computed here without canalsim's simulators:
//   LFOM     the closed-form step response of the fractional lag T D^λ y + y = K u through the
//            Mittag-Leffler function, y(t) = K (1 − E_λ(−t^λ / T)), summed over the steps of a
//            PRBS held between samples (as the recordings' command is), behind the delay L; read
//            with white noise and a 0.05 mm quantiser. The std must be useful (relative std
//            < 20 %) and cover the noise: the estimates lie within 3 std of the GL model's own
//            parameters for this truth (its noise-free fit), and over 8 noise seeds K within
//            2 std of them in most seeds (with a std 10 times too small it would in about one).
//            The GL model's bias against the continuous truth — its discretisation at h = 0.13 s,
//            which no noise std covers — is bounded separately.
//   LIOM     the continuous first-order lag's closed-form step response: with T and L held, K and
//            the operating point are a linear regression whose OLS std is known; with all
//            parameters fitted the std scales with the noise.
//   3 samples are refused ("too few"), never fitted with a confident std.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numbers>
#include <random>
#include <utility>

#include "core/errors.hpp"
#include "reduced_models/identification.hpp"
#include "testing/recordings.hpp"
#include "testing/synthetic.hpp"
#include "testing/refusals.hpp"

namespace canalsim::reduced {
namespace {

constexpr double kH = 0.13, kU0 = 20.0, kY0 = 45.0, kAmplitude = 5.0;
constexpr std::size_t kSamples = 3000, kRest = 20;

// E_α(−x^α) for 0 < α < 1 and x ≥ 0 by its spectral representation (Gorenflo & Mainardi 1997),
//   E_α(−x^α) = ∫_0^∞ e^{−r x} K_α(r) dr,  K_α(r) = r^{α−1} sin(απ) / (π (r^{2α} + 2 r^α cos(απ) + 1)),
// integrated by the trapezoidal rule in s = ln r (the integrand decays exponentially both ways).
double mittag_leffler_relaxation(double alpha, double x) {
  if (x <= 0.0) return 1.0;
  const double sine = std::sin(alpha * std::numbers::pi), cosine = std::cos(alpha * std::numbers::pi);
  constexpr double kFrom = -100.0, kTo = 40.0, kDs = 0.01;
  double sum = 0.0;
  for (double s = kFrom; s <= kTo; s += kDs) {
    const double r = std::exp(s), ra = std::pow(r, alpha);
    sum += std::exp(-r * x) * ra * sine / (std::numbers::pi * (ra * ra + 2.0 * ra * cosine + 1.0));
  }
  return sum * kDs;
}

struct Lfom {
  double K = 0.9, T = 1.25, lambda = 0.41, L = 4.9;
};

// The PRBS command of testing/synthetic.hpp (9-stage LFSR, clock 4 samples, ±5 mm).
std::vector<double> command() { return testing::prbs(kSamples, kRest, 4, kU0, kAmplitude); }

// The level of a linear system with unit-step response `step` (seconds after the delayed step)
// driven by `u` held from t_k to t_{k+1}, sampled at t_i: y0 + Σ_k Δu_k step(t_i − t_k − L).
std::vector<double> superposed(const std::vector<double>& u, double L, const std::function<double(double)>& step) {
  std::vector<double> unit(u.size());
  for (std::size_t m = 0; m < u.size(); ++m) unit[m] = step(static_cast<double>(m) * kH - L);
  std::vector<double> y(u.size(), kY0);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double du = u[k] - (k == 0 ? kU0 : u[k - 1]);
    if (du == 0.0) continue;
    for (std::size_t i = k; i < u.size(); ++i) y[i] += du * unit[i - k];
  }
  return y;
}

std::vector<double> lfom_truth(const Lfom& p) {
  const double tau = std::pow(p.T, 1.0 / p.lambda);  // t^λ / T = (t / τ)^λ
  return superposed(command(), p.L, [&](double t) {
    return t <= 0.0 ? 0.0 : p.K * (1.0 - mittag_leffler_relaxation(p.lambda, t / tau));
  });
}

std::vector<double> liom_truth(double K, double T, double L) {
  return superposed(command(), L, [&](double t) { return t <= 0.0 ? 0.0 : K * (1.0 - std::exp(-t / T)); });
}

// The recording of `level` read with white noise of `sigma` (seed) and a quantiser (0: none).
ExperimentData recording(const std::vector<double>& level, double sigma, unsigned seed, double quantum) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> t(level.size()), y(level.size());
  for (std::size_t k = 0; k < level.size(); ++k) {
    t[k] = kH * static_cast<double>(k);
    y[k] = level[k] + sigma * noise(rng);
    if (quantum > 0.0) y[k] = quantise(y[k], quantum);
  }
  return prepare_data(testing::command_and_level("truth.csv", std::move(t), command(), std::move(y)));
}

std::size_t index_of(const FitResult& r, const std::string& name) {
  const auto it = std::find(r.parameter_names.begin(), r.parameter_names.end(), name);
  EXPECT_NE(it, r.parameter_names.end()) << name;
  return static_cast<std::size_t>(it - r.parameter_names.begin());
}

// The true system has the whole memory: the fit simulates with it too (the paper's 500-term
// memory is 65 s here, and a λ = 0.41 lag remembers far longer).
FitOptions lfom_options() {
  FitOptions o;
  o.criterion = Criterion::least_squares;
  o.simulation.gl.memory = GlMemory::full;
  o.threads = 1;
  return o;
}

// The GL model's parameters for the independent truth: its fit to the noise-free levels. GL at
// h = 0.13 s is not the continuous lag (measured: L 0.062 s short, λ 0.009 high, K and T 1.5 %
// and 2.6 % low; a first-order scheme on a response that rises like t^λ), and no std from noise
// covers that: the std is checked against these values, and the bias is bounded separately.
const FitResult& noise_free_fit() {
  static const FitResult r = fit(ModelKind::lfom, recording(lfom_truth(Lfom{}), 0.0, 1, 0.0), lfom_options());
  return r;
}

TEST(FitStatistics, LfomStdIsUsefulAndCoversTheNoise) {
  const Lfom truth;
  const FitResult r = fit(ModelKind::lfom, recording(lfom_truth(truth), 0.05, 1, 0.05), lfom_options());
  const FitResult& reference = noise_free_fit();
  ASSERT_EQ(r.parameter_names, parameter_names(ModelKind::lfom));
  ASSERT_EQ(r.std.size(), 4u);
  EXPECT_GE(r.inflation, 1.0);
  const std::map<std::string, std::pair<double, double>> bias_bound{
      {"K", {truth.K, 0.03 * truth.K}}, {"T", {truth.T, 0.05 * truth.T}}, {"lambda", {truth.lambda, 0.02}}, {"L", {truth.L, 0.5 * kH}}};
  for (const auto& [name, expected] : bias_bound) {
    const auto [value, bound] = expected;
    const std::size_t j = index_of(r, name);
    const double estimate = get_parameter(r.model.p, name), gl = get_parameter(reference.model.p, name);
    std::printf("  %-6s true %.4g  GL model %.4g  estimate %.4g ± %.2g (numerical part %.2g)  (%.2f std from GL, %.2f from true)\n",
                name.c_str(), value, gl, estimate, r.std[j], r.numerical_std[j], (estimate - gl) / r.std[j],
                (estimate - value) / r.std[j]);
    ASSERT_TRUE(std::isfinite(r.std[j]) && r.std[j] > 0.0) << name;
    EXPECT_LT(r.std[j] / value, 0.2) << name;
    EXPECT_LT(std::abs(estimate - gl), 3.0 * r.std[j]) << name;
    EXPECT_LT(std::abs(gl - value), bound) << name << ": the GL discretisation's bias";
    EXPECT_DOUBLE_EQ(r.correlation[j][j], 1.0);
  }
  // The delay's bias is the time step's (about half a step early): the numerical part of its std,
  // from the model computed at h/2 and h/4, covers it. (K's and T's biases at this fast PRBS,
  // a switch every 4 samples, come from the t^λ rise after each switch and are larger than that
  // extrapolation says: bounded above, not covered.)
  const std::size_t l = index_of(r, "L");
  EXPECT_GT(r.numerical_std[l], 0.2 * kH);
  EXPECT_LT(std::abs(get_parameter(r.model.p, "L") - truth.L), 3.0 * r.std[l]);
  std::printf("  inflation %.2f; correlation K-T %.2f, T-lambda %.2f, T-L %.2f\n", r.inflation,
              r.correlation[index_of(r, "K")][index_of(r, "T")], r.correlation[index_of(r, "T")][index_of(r, "lambda")],
              r.correlation[index_of(r, "T")][index_of(r, "L")]);
}

// Coverage: with the right std, |K − K_GL| < 2 std in about 95 % of the seeds (7.6 of 8; 6 or
// more with probability 0.99); with a std 10 times too small in about 16 % (1.3 of 8; 6 or more
// with probability 3e-4).
TEST(FitStatistics, LfomGainStdCoversTheScatterOverNoiseSeeds) {
  const std::vector<double> level = lfom_truth(Lfom{});
  const double K_gl = noise_free_fit().model.p.K;
  int covered = 0;
  for (unsigned seed = 11; seed < 19; ++seed) {
    const FitResult r = fit(ModelKind::lfom, recording(level, 0.05, seed, 0.05), lfom_options());
    const double K = r.model.p.K, std = r.std[index_of(r, "K")];
    std::printf("  seed %u: K %.4f ± %.4f (%.2f std from the GL model's %.4f), inflation %.2f\n", seed, K, std,
                (K - K_gl) / std, K_gl, r.inflation);
    covered += std::abs(K - K_gl) < 2.0 * std;
  }
  EXPECT_GE(covered, 6);
}

// LIOM with T and L held (bounds lo == hi): the output is y0 + c + K g with g known, a linear
// regression on white noise whose OLS std of K is s / sqrt(Σ (g − ḡ)²), s² = Σ e² / (N − 2).
// The held parameters report std 0 and no correlation.
TEST(FitStatistics, HeldDynamicsGiveTheOrdinaryLeastSquaresStdOfTheGain) {
  const double K = 0.7, T = 3.0, L = 1.3, sigma = 0.1;
  const ExperimentData data = recording(liom_truth(K, T, L), sigma, 5, 0.0);
  FitOptions o;
  o.criterion = Criterion::least_squares;
  o.bounds.T = {T, T, std::nullopt, false};
  o.bounds.L = {L, L, std::nullopt, false};
  const FitResult r = fit(ModelKind::liom, data, o);
  const std::vector<double> g = liom_truth(1.0, T, L);
  double mean = 0.0;
  for (double v : g) mean += (v - kY0) / static_cast<double>(g.size());
  double energy = 0.0, sse = 0.0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    energy += (g[k] - kY0 - mean) * (g[k] - kY0 - mean);
    const double e = r.response.front()[k] - data.y_dwe_mm[k];
    sse += e * e;
  }
  const double ols = std::sqrt(sse / static_cast<double>(g.size() - 2) / energy);
  const std::size_t k = index_of(r, "K");
  std::printf("  K %.4f ± %.5f, OLS %.5f, inflation %.3f\n", r.model.p.K, r.std[k], ols, r.inflation);
  EXPECT_NEAR(r.std[k], ols, 0.1 * ols);
  EXPECT_LT(std::abs(r.model.p.K - K), 3.0 * r.std[k]);
  EXPECT_EQ(r.std[index_of(r, "T")], 0.0);
  EXPECT_EQ(r.std[index_of(r, "L")], 0.0);
  EXPECT_TRUE(std::isnan(r.correlation[k][index_of(r, "T")]));
}

// All of LIOM's parameters fitted: the same noise, twice as large, doubles every std.
TEST(FitStatistics, StdScalesWithTheNoise) {
  const std::vector<double> level = liom_truth(0.7, 3.0, 1.3);
  FitOptions o;
  o.criterion = Criterion::least_squares;
  const FitResult once = fit(ModelKind::liom, recording(level, 0.05, 9, 0.0), o);
  const FitResult twice = fit(ModelKind::liom, recording(level, 0.10, 9, 0.0), o);
  for (const std::string name : {"K", "T", "L"}) {
    const double ratio = twice.std[index_of(twice, name)] / once.std[index_of(once, name)];
    std::printf("  %s: std %.3g -> %.3g (x%.2f)\n", name.c_str(), once.std[index_of(once, name)],
                twice.std[index_of(twice, name)], ratio);
    EXPECT_NEAR(ratio, 2.0, 0.3) << name;
  }
}

TEST(FitStatistics, ThreeSamplesAreTooFewToFit) {
  const ExperimentData data =
      prepare_data(testing::command_and_level("few.csv", {0.0, 0.13, 0.26}, {20.0, 25.0, 25.0}, {45.0, 45.0, 45.5}));
  EXPECT_TRUE(testing::refuses_input([&] { (void)fit(ModelKind::lfom, data); }, "too few"));
}

}  // namespace
}  // namespace canalsim::reduced
