// Sensors (scenarios/sensors.*): sampling, quantisation (paper eq. 17), noise, delay, offset.
#include "scenarios/sensors.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <numeric>
#include <random>
#include <stdexcept>

#include "testing/refusals.hpp"

namespace canalsim {
namespace {

SensorOptions ideal(double period = 0.13) {
  SensorOptions options;
  options.sample_period = period;
  options.resolution = 0.0;
  return options;
}

TEST(Quantise, IsPaperEquation17) {
  const double r = 0.05e-3;
  EXPECT_NEAR(quantise(50.123e-3, r), 50.10e-3, 1e-15);  // nint(1002.46) = 1002
  EXPECT_NEAR(quantise(50.130e-3, r), 50.15e-3, 1e-15);  // nint(1002.6) = 1003
  EXPECT_NEAR(quantise(-0.03e-3, r), -0.05e-3, 1e-18);
  EXPECT_EQ(quantise(0.0123, 0.0), 0.0123);
}

TEST(Quantise, OutputIsAMultipleOfTheResolutionWithinHalfAStep) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> level(-0.2, 0.2);
  for (double r : {0.05e-3, 1e-3, 0.3}) {
    for (int i = 0; i < 10000; ++i) {
      const double y = level(rng);
      const double q = quantise(y, r);
      EXPECT_NEAR(q / r, std::round(q / r), 1e-6) << y;
      EXPECT_LE(std::abs(q - y), 0.5 * r * (1 + 1e-9)) << y;
    }
  }
}

TEST(Sensor, SamplesAtTheExperimentPeriod) {
  Sensor sensor;  // level sensor defaults: 0.13 s, 0.05 mm
  for (double t = 0.0; t <= 255.5 + 1e-9; t += 0.01) sensor.observe(t, 0.05);
  // floor(255.5 / 0.13) + 1 = 1966 samples at k * 0.13 s.
  ASSERT_EQ(sensor.times().size(), 1966u);
  EXPECT_NEAR(sensor.times()[1965], 1965 * 0.13, 1e-12);
  EXPECT_NEAR(sensor.values()[100], 0.05, 1e-15);
}

TEST(Sensor, InterpolatesBetweenSolverStepsExactlyForALinearSignal) {
  Sensor sensor(ideal());
  const auto f = [](double t) { return 0.04 + 0.001 * t; };
  for (double t = 0.0; t < 20.0; t += 0.0371) sensor.observe(t, f(t));
  for (std::size_t k = 0; k < sensor.times().size(); ++k) {
    EXPECT_NEAR(sensor.values()[k], f(sensor.times()[k]), 1e-15) << k;
  }
}

TEST(Sensor, DelayShiftsByTheExactNumberOfSamples) {
  const auto f = [](double t) { return 0.05 + 0.01 * std::sin(0.7 * t) + 0.001 * t; };
  for (int lag : {1, 3, 38}) {
    SensorOptions delayed_options = ideal();
    delayed_options.delay = lag * 0.13;
    Sensor plain(ideal()), delayed(delayed_options);
    for (double t = 0.0; t < 30.0; t += 0.0117) {
      plain.observe(t, f(t));
      delayed.observe(t, f(t));
    }
    ASSERT_EQ(plain.values().size(), delayed.values().size());
    for (std::size_t k = 0; k < plain.values().size(); ++k) {
      const double expected = k >= static_cast<std::size_t>(lag) ? plain.values()[k - lag] : f(0.0);
      EXPECT_NEAR(delayed.values()[k], expected, 1e-14) << lag << ' ' << k;
    }
  }
}

// A negative delay (the level logger's clock ahead of the command's): sample k reads the signal
// `lead` periods later, emitted once that instant has been observed; finish() owes the last ones,
// which read past the run's end and take its last value.
TEST(Sensor, ANegativeDelayLeadsByTheExactNumberOfSamples) {
  const auto f = [](double t) { return 0.05 + 0.01 * std::sin(0.7 * t) + 0.001 * t; };
  for (int lead : {1, 3, 38}) {
    SensorOptions leading_options = ideal();
    leading_options.delay = -lead * 0.13;
    Sensor plain(ideal()), leading(leading_options);
    double last_t = 0.0;
    for (double t = 0.0; t < 30.0; t += 0.0117) {
      plain.observe(t, f(t));
      leading.observe(t, f(t));
      last_t = t;
      // Nothing is emitted before the instant it reads has been observed.
      if (!leading.times().empty()) {
        EXPECT_LE(leading.times().back() + lead * 0.13, t + 1e-9);
      }
    }
    const std::size_t n = plain.values().size();
    ASSERT_EQ(leading.values().size() + static_cast<std::size_t>(lead), n) << lead;
    leading.finish(n);
    ASSERT_EQ(leading.values().size(), n);
    for (std::size_t k = 0; k < n; ++k) {
      const double expected = k + lead < n ? plain.values()[k + lead] : f(last_t);
      EXPECT_NEAR(leading.values()[k], expected, 1e-14) << lead << ' ' << k;
      EXPECT_NEAR(leading.times()[k], plain.times()[k], 1e-12);
    }
  }
}

TEST(Sensor, DelayWithQuantisationStillShiftsExactly) {
  SensorOptions plain_options;  // 0.05 mm
  SensorOptions delayed_options;
  delayed_options.delay = 4 * 0.13;
  Sensor plain(plain_options), delayed(delayed_options);
  const auto f = [](double t) { return 0.05 + 0.002 * std::sin(t); };
  plain.sample(f, 500);
  delayed.sample(f, 500);
  for (std::size_t k = 4; k < 500; ++k) EXPECT_EQ(delayed.values()[k], plain.values()[k - 4]) << k;
}

TEST(Sensor, NoiseHasTheRequestedStandardDeviation) {
  SensorOptions options = ideal();
  options.noise_std = 1e-3;
  options.seed = 2024;
  Sensor sensor(options);
  const std::size_t n = 20000;
  sensor.sample([](double) { return 0.05; }, n);
  const auto& v = sensor.values();
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double sq = 0.0;
  for (double x : v) sq += (x - mean) * (x - mean);
  const double std_dev = std::sqrt(sq / (n - 1));
  // Sampling error of a standard deviation: sigma / sqrt(2 n) = 0.5 %; allow 4 of them.
  EXPECT_NEAR(std_dev, 1e-3, 4 * 1e-3 / std::sqrt(2.0 * n));
  EXPECT_NEAR(mean, 0.05, 4 * 1e-3 / std::sqrt(double(n)));
  std::printf("noise: requested std 1.000 mm, measured %.4f mm over %zu samples\n", std_dev * 1e3, n);
}

TEST(Sensor, NoiseIsReproducibleForASeedAndDiffersBetweenSeeds) {
  SensorOptions options = ideal();
  options.noise_std = 1e-3;
  Sensor a(options), b(options);
  options.seed = 99;
  Sensor c(options);
  for (Sensor* s : {&a, &b, &c}) s->sample([](double) { return 0.0; }, 100);
  EXPECT_EQ(a.values(), b.values());
  EXPECT_NE(a.values(), c.values());
}

TEST(Sensor, OffsetIsAddedBeforeQuantisation) {
  SensorOptions options;
  options.offset = 0.26e-3;
  Sensor sensor(options);
  sensor.observe(0.0, 0.05);
  EXPECT_NEAR(sensor.values()[0], 0.05025, 1e-12);  // 50.26 mm -> 50.25 mm
}

TEST(Sensor, RejectsTimeGoingBackwards) {
  Sensor sensor;
  sensor.observe(1.0, 0.05);
  EXPECT_THROW(sensor.observe(0.5, 0.05), std::invalid_argument);
}

TEST(SensorOptions, DefaultsPerKind) {
  EXPECT_EQ(SensorOptions::defaults_for(SensorKind::level).resolution, 0.05e-3);
  EXPECT_EQ(SensorOptions::defaults_for(SensorKind::gate_position).resolution, 0.0);
  EXPECT_EQ(SensorOptions::defaults_for(SensorKind::flow).sample_period, 0.13);
}

TEST(SensorOptions, ValidationNamesTheFieldAndRange) {
  using testing::validation_message;
  EXPECT_TRUE(SensorOptions{}.validate());
  EXPECT_EQ(validation_message<SensorOptions>([](auto& o) { o.sample_period = 0.0; }),
            "sample_period = 0: expected a value in (0, 3600] s");
  EXPECT_EQ(validation_message<SensorOptions>([](auto& o) { o.noise_std = -1.0; }),
            "noise_std = -1: expected a value in [0, 100]");
  EXPECT_EQ(validation_message<SensorOptions>([](auto& o) { o.delay = 700.0; }),
            "delay = 700: expected a value in [-600, 600] s");
  SensorOptions options;
  options.delay = 700.0;
  EXPECT_THROW(Sensor{options}, std::invalid_argument);
}

}  // namespace
}  // namespace canalsim
