// Discrepancy model: the filter fitted from the command to the residual recovers a known lag with
// a delay (generated in continuous time, not by the fitted difference equation), calls a gain
// static, finds nothing in white noise, and leaves per-recording offsets to the offsets alone.
#include "diagnosis/discrepancy.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "testing/signals.hpp"

namespace canalsim::diagnosis {
namespace {

using testing::white_noise;

constexpr double h = 0.13;           // the canal's sampling period [s]
constexpr std::size_t samples = 1500;
constexpr std::size_t fitted = 1000;

// A PRBS-like command: the operating point for 20 samples, then u0 ± amplitude at random, each
// level held for 5..40 samples.
std::vector<double> prbs(double u0, double amplitude, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> hold(5, 40);
  std::bernoulli_distribution up(0.5);
  std::vector<double> u(samples);
  double level = u0;
  std::size_t next = 20;
  for (std::size_t k = 0; k < samples; ++k) {
    if (k == next) {
      level = u0 + (up(rng) ? amplitude : -amplitude);
      next += static_cast<std::size_t>(hold(rng));
    }
    u[k] = level;
  }
  return u;
}

// K e^{−τ_d s}/(1 + τ s) driven by the command held between samples, from rest on the operating
// point, solved exactly between switches: over [kh, (k+1)h] the delayed command u(t − τ_d) is
// u(k − m − 1) until kh + f·h and u(k − m) after, with τ_d = (m + f) h.
std::vector<double> delayed_lag(const std::vector<double>& u, double gain, double tau, double delay) {
  const auto m = static_cast<std::ptrdiff_t>(std::floor(delay / h));
  const double f = delay / h - static_cast<double>(m);
  const auto held = [&](std::ptrdiff_t i) { return u[static_cast<std::size_t>(std::max<std::ptrdiff_t>(i, 0))]; };
  double x = gain * u.front();
  const auto settle = [&](double target, double span) { x = target + (x - target) * std::exp(-span / tau); };
  std::vector<double> y(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) {
    y[k] = x;
    const auto i = static_cast<std::ptrdiff_t>(k);
    settle(gain * held(i - m - 1), f * h);
    settle(gain * held(i - m), (1.0 - f) * h);
  }
  return y;
}

// Three recordings at three operating points; residual = truth(u) + white noise of `sigma`.
std::vector<DiscrepancyRecording> recordings(const std::function<std::vector<double>(const std::vector<double>&, int)>& truth,
                                             double sigma) {
  std::vector<DiscrepancyRecording> out;
  const double operating_points[] = {120.0, 160.0, 200.0};
  for (int r = 0; r < 3; ++r) {
    DiscrepancyRecording rec;
    rec.u = prbs(operating_points[r], 15.0, 10 + static_cast<std::uint64_t>(r));
    rec.residual = truth(rec.u, r);
    const auto noise = white_noise(samples, 20 + static_cast<std::uint64_t>(r), sigma);
    for (std::size_t k = 0; k < samples; ++k) rec.residual[k] += noise[k];
    rec.n_fit = fitted;
    out.push_back(std::move(rec));
  }
  return out;
}

void record(const DiscrepancyModel& m) {
  ::testing::Test::RecordProperty("form", m.form);
  ::testing::Test::RecordProperty("structure", std::to_string(m.poles) + " poles, " + std::to_string(m.numerator) +
                                                   " numerator terms, delay " + std::to_string(m.delay_s) + " s");
  std::string coefficients;
  for (double v : m.a) coefficients += "a " + std::to_string(v) + " ";
  for (double v : m.b) coefficients += "b " + std::to_string(v) + " ";
  ::testing::Test::RecordProperty("coefficients", coefficients);
  ::testing::Test::RecordProperty("static_gain", std::to_string(m.static_gain));
  ::testing::Test::RecordProperty("band_hz", std::to_string(m.band_low_hz) + ".." + std::to_string(m.band_high_hz) +
                                                 " (command " + std::to_string(m.command_band_hz) + ")");
  ::testing::Test::RecordProperty("heldout_rms", std::to_string(m.heldout_rms_before) + " -> " +
                                                     std::to_string(m.heldout_rms_after));
  ::testing::Test::RecordProperty("heldout_share_removed", std::to_string(m.heldout_share_removed));
  ::testing::Test::RecordProperty("offsets_share_removed", std::to_string(m.offsets_share_removed));
}

TEST(DiscrepancyModel, RecoversADelayedFirstOrderLag) {
  const double gain = 0.4, tau = 3.0, delay = 2.3;  // delay = 17.7 samples
  const auto recs = recordings([&](const std::vector<double>& u, int) { return delayed_lag(u, gain, tau, delay); }, 0.2);
  const DiscrepancyModel m = fit_discrepancy("y_dwe_mm", recs, h);
  record(m);
  ASSERT_TRUE(m.found);
  EXPECT_EQ(m.form, "dynamic");
  EXPECT_NEAR(m.static_gain / gain, 1.0, 0.05);
  EXPECT_LE(std::abs(m.delay_s - delay), h);
  EXPECT_GT(m.heldout_share_removed, 0.8);
  // The offsets alone leave the lag's transients; the filter removes them too.
  const double offsets_mse = m.heldout_rms_before * m.heldout_rms_before * (1.0 - m.offsets_share_removed);
  EXPECT_GT(1.0 - m.heldout_rms_after * m.heldout_rms_after / offsets_mse, 0.8);
  // The exact discrete equivalent has one pole, e^{−h/τ}.
  ASSERT_EQ(m.poles, 1);
  EXPECT_NEAR(-h / std::log(-m.a[0]) / tau, 1.0, 0.05);
  // A first-order lag falls 3 dB at 1/(2πτ).
  EXPECT_NEAR(m.band_high_hz * 2.0 * std::numbers::pi * tau, 1.0, 0.1);
  // The offsets are the lag's steady state on each operating point.
  ASSERT_EQ(m.offsets.size(), 3u);
  EXPECT_NEAR(m.offsets[0], gain * 120.0, 0.5);
}

TEST(DiscrepancyModel, CallsAnErrorProportionalToTheCommandStatic) {
  const auto recs = recordings([](const std::vector<double>& u, int) {
    std::vector<double> e(u.size());
    for (std::size_t k = 0; k < u.size(); ++k) e[k] = 0.03 * u[k];
    return e;
  }, 0.1);
  const DiscrepancyModel m = fit_discrepancy("y_dwe_mm", recs, h);
  record(m);
  ASSERT_TRUE(m.found);
  EXPECT_EQ(m.form, "static");
  EXPECT_NEAR(m.static_gain / 0.03, 1.0, 0.05);
}

TEST(DiscrepancyModel, FindsNothingInWhiteNoise) {
  const auto recs = recordings([](const std::vector<double>& u, int) { return std::vector<double>(u.size(), 0.0); }, 1.0);
  const DiscrepancyModel m = fit_discrepancy("y_dwe_mm", recs, h);
  record(m);
  EXPECT_FALSE(m.found);
  EXPECT_EQ(m.form, "none");
}

TEST(DiscrepancyModel, LeavesPerRecordingOffsetsToTheOffsetsAlone) {
  const double offsets[] = {2.0, -1.5, 3.0};
  const auto recs = recordings([&](const std::vector<double>& u, int r) { return std::vector<double>(u.size(), offsets[r]); }, 0.2);
  const DiscrepancyModel m = fit_discrepancy("y_dwe_mm", recs, h);
  record(m);
  EXPECT_FALSE(m.found);
  EXPECT_EQ(m.form, "static");
  EXPECT_EQ(m.poles + m.numerator, 0);
  ASSERT_EQ(m.offsets.size(), 3u);
  for (int r = 0; r < 3; ++r) EXPECT_NEAR(m.offsets[static_cast<std::size_t>(r)], offsets[r], 0.03);
  EXPECT_GT(m.heldout_share_removed, 0.9);
}

void expect_invalid(const std::function<void()>& call, const std::string& field) {
  try {
    call();
    ADD_FAILURE() << "no exception; expected one naming " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(DiscrepancyOptions, InvalidInputsNameTheirField) {
  const auto recs = recordings([](const std::vector<double>& u, int) { return std::vector<double>(u.size(), 0.0); }, 1.0);
  const auto with = [&](auto change, const std::string& field) {
    DiscrepancyOptions o;
    change(o);
    expect_invalid([&] { (void)fit_discrepancy("c", recs, h, o); }, field);
  };
  with([](DiscrepancyOptions& o) { o.max_poles = -1; }, "max_poles");
  with([](DiscrepancyOptions& o) { o.max_numerator = 0; }, "max_numerator");
  with([](DiscrepancyOptions& o) { o.max_delay_s = std::nan(""); }, "max_delay_s");
  with([](DiscrepancyOptions& o) { o.min_heldout_gain = 1.0; }, "min_heldout_gain");
  expect_invalid([&] { (void)fit_discrepancy("c", recs, 0.0); }, "period_s");
  expect_invalid([&] { (void)fit_discrepancy("c", {}, h); }, "recordings");
  auto short_residual = recs;
  short_residual[1].residual.pop_back();
  expect_invalid([&] { (void)fit_discrepancy("c", short_residual, h); }, "residual");
  auto no_heldout = recs;
  no_heldout[2].n_fit = samples;
  expect_invalid([&] { (void)fit_discrepancy("c", no_heldout, h); }, "n_fit");
}

}  // namespace
}  // namespace canalsim::diagnosis
