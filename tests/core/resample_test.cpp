// core/resample: a known signal with jittered time stamps, resampled to a coarser period. A slow
// sinusoid (within the passband) comes out with its amplitude and phase; a fast one above the new
// Nyquist frequency, which plain sampling would fold onto a slow alias, is removed; the gate
// command is held, not smoothed.
#include "core/resample.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <utility>

#include "testing/recordings.hpp"

namespace canalsim {
namespace {

constexpr double kPi = std::numbers::pi;

// 128 Hz logger with ±30 % jitter on each step: y = 2 sin(2π 0.2 t) + 0.5 sin(2π 7.3 t) + 60,
// and a gate step from 20 to 25 mm at t = 10.4 s.
Recording jittered_recording() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<double> t, u, y;
  for (double time = 0.0; time < 30.0; time += (1.0 + jitter(rng)) / 128.0) {
    t.push_back(time);
    u.push_back(time >= 10.4 ? 25.0 : 20.0);
    y.push_back(60.0 + 2.0 * std::sin(2.0 * kPi * 0.2 * time) + 0.5 * std::sin(2.0 * kPi * 7.3 * time));
  }
  return testing::command_and_level("logger.csv", std::move(t), std::move(u), std::move(y));
}

TEST(Resample, KeepsThePassbandRemovesWhatWouldAliasAndHoldsTheCommand) {
  ResampleOptions o;
  o.period_s = 0.125;  // Nyquist 4 Hz: 7.3 Hz would alias to 0.7 Hz
  const Recording out = resample(jittered_recording(), o);
  const auto& t = out.column("t_s");
  const auto& y = out.column("y_dwe_mm");
  const auto& u = out.column("u_mm");
  ASSERT_EQ(t.size(), static_cast<std::size_t>(std::floor(t.back() / 0.125 + 1e-9)) + 1);
  EXPECT_NEAR(t[1] - t[0], 0.125, 1e-12);
  double worst = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_EQ(u[k], t[k] >= 10.4 ? 25.0 : 20.0) << t[k];
    if (t[k] < 3.0 || t[k] > t.back() - 3.0) continue;  // the filter's half-length at the edges
    const double slow = 60.0 + 2.0 * std::sin(2.0 * kPi * 0.2 * t[k]);
    worst = std::max(worst, std::abs(y[k] - slow));
  }
  // The 0.5 mm component above the new Nyquist frequency is gone (plain sampling would leave it
  // whole, as a 0.7 Hz alias); the slow one is kept to the linear interpolation's error.
  EXPECT_LT(worst, 0.01);
  EXPECT_EQ(out.meta("resampled_period_s"), "0.125");
}

TEST(Resample, BadPeriodsAreOneLineErrorsNamingTheSource) {
  ResampleOptions o;
  o.period_s = 0.0;
  EXPECT_THROW(resample(jittered_recording(), o), InputError);
  o.period_s = 100.0;
  try {
    resample(jittered_recording(), o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("logger.csv: period 100 s is longer than the recording", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace canalsim
