// Ticks worked out by hand: steps of 1, 2 or 5 times a power of ten, zero written as 0, decades.
#include <gtest/gtest.h>

#include <cmath>

#include "plot/ticks.hpp"

namespace {

using namespace canalsim::plot;

std::vector<std::string> labels(const std::vector<double>& ticks, double step) {
  std::vector<std::string> out;
  for (const double v : ticks) out.push_back(tick_label(v, step));
  return out;
}

TEST(NiceTicks, ARangeFromZeroTo0_37IsTickedEveryTenth) {
  // Span 0.37 over 5 intervals is 0.074: the next of 1, 2, 5 × 10^k is 0.1.
  EXPECT_DOUBLE_EQ(tick_step(0.0, 0.37), 0.1);
  const std::vector<double> ticks = nice_ticks(0.0, 0.37);
  EXPECT_EQ(ticks, (std::vector<double>{0.0, 0.1, 0.2, 0.3}));  // exactly 0.3, not 0.30000000000000004
  EXPECT_EQ(labels(ticks, 0.1), (std::vector<std::string>{"0", "0.1", "0.2", "0.3"}));
}

TEST(NiceTicks, APhaseDownToMinus1780DegreesIsTickedEvery500) {
  // Span 1800 / 5 = 360 → 500; the multiples of 500 inside [-1780, 20].
  const std::vector<double> ticks = nice_ticks(-1780.0, 20.0);
  EXPECT_EQ(ticks, (std::vector<double>{-1500.0, -1000.0, -500.0, 0.0}));
  EXPECT_EQ(labels(ticks, 500.0), (std::vector<std::string>{"-1500", "-1000", "-500", "0"}));
}

TEST(NiceTicks, ATinyRangeAroundZeroKeepsAnExactZeroAndReadableLabels) {
  // Span 2e-9 / 5 = 4e-10 → 5e-10.
  const std::vector<double> ticks = nice_ticks(-1e-9, 1e-9);
  ASSERT_EQ(ticks.size(), 5u);
  EXPECT_EQ(ticks[2], 0.0);
  EXPECT_FALSE(std::signbit(ticks[2]));
  EXPECT_DOUBLE_EQ(ticks[0], -1e-9);
  EXPECT_DOUBLE_EQ(ticks[4], 1e-9);
  EXPECT_EQ(labels(ticks, 5e-10), (std::vector<std::string>{"-1e-09", "-5e-10", "0", "5e-10", "1e-09"}));
}

TEST(NiceTicks, StepsAreOneTwoOrFiveTimesAPowerOfTen) {
  EXPECT_DOUBLE_EQ(nice_step(0.074), 0.1);
  EXPECT_DOUBLE_EQ(nice_step(0.1), 0.1);
  EXPECT_DOUBLE_EQ(nice_step(1.3), 2.0);
  EXPECT_DOUBLE_EQ(nice_step(2.1), 5.0);
  EXPECT_DOUBLE_EQ(nice_step(360.0), 500.0);
  EXPECT_DOUBLE_EQ(nice_step(6.0), 10.0);
  EXPECT_DOUBLE_EQ(tick_step(-0.5, 0.5, 4), 0.5);  // a calm residual axis: -0.5, 0, 0.5
}

TEST(TickLabels, ZeroAndRoundingNoiseNeverReadMinusZero) {
  EXPECT_EQ(tick_label(0.0, 0.01), "0");
  EXPECT_EQ(tick_label(-0.0, 0.01), "0");
  EXPECT_EQ(tick_label(-1e-17, 0.1), "0");  // a tick that rounding left a hair below zero
  EXPECT_EQ(tick_label(-0.25, 0.05), "-0.25");
  EXPECT_EQ(tick_label(2.5, 0.5), "2.5");
  EXPECT_EQ(tick_label(1200.0, 200.0), "1200");
  EXPECT_EQ(tick_label(3e6, 1e6), "3e+06");
}

TEST(LogAxis, DecadesAndTheirMinorTicks) {
  EXPECT_EQ(log_decades(0.03, 200.0), (std::vector<double>{0.1, 1.0, 10.0, 100.0}));
  EXPECT_EQ(log_decades(1e-3, 1e-1), (std::vector<double>{1e-3, 1e-2, 1e-1}));
  EXPECT_EQ(log_minor_ticks(1.0, 10.0), (std::vector<double>{2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(log_minor_ticks(0.5, 3.0), (std::vector<double>{0.5, 0.6, 0.7, 0.8, 0.9, 2, 3}));
  EXPECT_EQ(log_tick_label(0.01), "0.01");
  EXPECT_EQ(log_tick_label(1000.0), "1000");
  EXPECT_EQ(log_tick_label(1e5), "1e+05");
  EXPECT_EQ(log_tick_label(1e-5), "1e-05");
}

}  // namespace
