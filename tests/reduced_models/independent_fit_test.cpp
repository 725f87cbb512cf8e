// Our LIOM fit against an independent least-squares fit of the same model, written here from
// scratch, on a truth the LIOM cannot represent (two lags in series, 40 s and 4 s, behind a 2 s
// delay) read by a realistic sensor (testing/realistic.hpp: offset, drift, noise, quantisation on
// an offset lattice, jittered sampling). The acceptance on real recordings: "delays
// must be physical and the fits as good as an independent least-squares fit of the same model".
//
// The independent fit uses the closed-form step response of the continuous first-order lag,
// y(t) = c + K A (1 − e^{−(t − t_s − L)/T}) after t_s + L (no simulator of ours): a brute-force
// grid over L in steps of h/4, a golden-section search over log T at each L, and the offset c and
// gain K by linear least squares.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

#include "reduced_models/identification.hpp"
#include "testing/realistic.hpp"
#include "testing/recordings.hpp"

namespace canalsim::reduced {
namespace {

constexpr double kH = 0.125, kA = 5.0, kStep = 10.0;

Recording two_lag_step(double K, double T1, double T2, double L) {
  const auto n = static_cast<std::size_t>(600.0 / kH);
  std::vector<double> t(n), u(n), y(n);
  for (std::size_t k = 0; k < n; ++k) {
    t[k] = kH * static_cast<double>(k);
    u[k] = t[k] >= kStep - 1e-9 ? 20.0 + kA : 20.0;
    const double tau = t[k] - kStep - L;
    y[k] = 45.0 + (tau > 0.0 ? K * kA * (1.0 - (T1 * std::exp(-tau / T1) - T2 * std::exp(-tau / T2)) / (T1 - T2)) : 0.0);
  }
  return testing::command_and_level("two_lags.csv", std::move(t), std::move(u), std::move(y));
}

struct IndependentFit {
  double K = 0.0, T = 0.0, L = 0.0, sse = std::numeric_limits<double>::infinity();
};

// SSE of the best (c, K) for a given (T, L), by the 2×2 normal equations.
IndependentFit least_squares_at(const std::vector<double>& t, const std::vector<double>& y, double T, double L) {
  double n = 0, sg = 0, sgg = 0, sy = 0, sgy = 0, syy = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double tau = t[k] - kStep - L;
    const double g = tau > 0.0 ? kA * (1.0 - std::exp(-tau / T)) : 0.0;
    n += 1;
    sg += g;
    sgg += g * g;
    sy += y[k];
    sgy += g * y[k];
    syy += y[k] * y[k];
  }
  const double det = n * sgg - sg * sg;
  const double K = (n * sgy - sg * sy) / det, c = (sy - K * sg) / n;
  IndependentFit f;
  f.K = K;
  f.T = T;
  f.L = L;
  f.sse = syy - 2.0 * c * sy - 2.0 * K * sgy + n * c * c + 2.0 * c * K * sg + K * K * sgg;
  return f;
}

IndependentFit independent_least_squares(const std::vector<double>& t, const std::vector<double>& y) {
  IndependentFit best;
  const double phi = (std::sqrt(5.0) - 1.0) / 2.0;
  for (double L = 0.0; L <= 20.0; L += kH / 4.0) {
    double a = std::log(1.0), b = std::log(1000.0);
    double x1 = b - phi * (b - a), x2 = a + phi * (b - a);
    IndependentFit f1 = least_squares_at(t, y, std::exp(x1), L), f2 = least_squares_at(t, y, std::exp(x2), L);
    for (int i = 0; i < 60; ++i) {
      if (f1.sse < f2.sse) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - phi * (b - a);
        f1 = least_squares_at(t, y, std::exp(x1), L);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + phi * (b - a);
        f2 = least_squares_at(t, y, std::exp(x2), L);
      }
    }
    for (const auto& f : {f1, f2}) {
      if (f.sse < best.sse) best = f;
    }
  }
  return best;
}

TEST(IndependentLeastSquares, OurFitIsAsGoodAsABruteForceLeastSquaresFitOnARealisticRecording) {
  testing::SensorRealism sensor;
  sensor.offset_mm = 0.4;
  sensor.drift_mm_per_s = 2e-5;
  sensor.noise_std_mm = 0.03;
  sensor.quantum_mm = 0.1;
  sensor.quantum_offset_mm = 0.037;
  sensor.jitter_std_s = 0.01;
  const auto rec = testing::realistic_levels(two_lag_step(1.5, 40.0, 4.0, 2.0), sensor);
  const auto& t = rec.column("t_s");
  const auto& y = rec.column("y_dwe_mm");
  const IndependentFit reference = independent_least_squares(t, y);
  const auto data = prepare_data(rec);
  FitOptions o;
  o.criterion = Criterion::least_squares;
  const FitResult ours = fit(ModelKind::liom, data, o);
  double sse = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) sse += std::pow(ours.response.front()[k] - y[k], 2);
  // As good: our sum of squares within 0.5 % of the brute-force fit's (measured: 0.15 % above
  // it — the polish fits the quantising sensor's mean reading, not the readings' squares; the
  // delays differ by 0.01 s, under the reference's h/4 grid).
  EXPECT_LE(sse, reference.sse * 1.005) << "ours K " << ours.model.p.K << " T " << ours.model.p.T << " L " << ours.model.p.L << " y0 " << ours.y0_mm.front() << " independent K " << reference.K << " T " << reference.T << " L " << reference.L;
  EXPECT_NEAR(ours.model.p.L, reference.L, kH / 4.0);
  EXPECT_NEAR(ours.model.p.T, reference.T, 0.01 * reference.T);
  EXPECT_NEAR(ours.model.p.K, reference.K, 0.01 * reference.K);
  // Physical: the first-order fit of two lags puts its delay between the true delay and the
  // delay plus the faster lag (the lag of 4 s is mostly seen as dead time).
  EXPECT_GT(ours.model.p.L, 2.0);
  EXPECT_LT(ours.model.p.L, 2.0 + 4.0);
  // The paper's IAE fit is no worse in Nrmse than the least-squares one by more than a point.
  const FitResult iae_fit = fit(ModelKind::liom, data);
  EXPECT_GT(iae_fit.nrmse.front(), ours.nrmse.front() - 1.0);
  EXPECT_NEAR(iae_fit.model.p.L, reference.L, 0.5);
}

}  // namespace
}  // namespace canalsim::reduced
