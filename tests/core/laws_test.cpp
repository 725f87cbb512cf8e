// The paper's laws written once (core/laws.hpp), against hand computations.
#include "core/laws.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace canalsim::laws {
namespace {

TEST(Quantise, RoundsToTheNearestStepAndHalvesAwayFromZero) {
  EXPECT_DOUBLE_EQ(quantise(60.012, 0.05), 60.0);
  EXPECT_DOUBLE_EQ(quantise(60.026, 0.05), 60.05);
  // Exact ties (binary-exact values): half away from zero, not to even. nearbyint would give 2
  // and -2 here; the sensors, the reduced models and the diagnosis all read 3 and -3.
  EXPECT_EQ(quantise(2.5, 1.0), 3.0);
  EXPECT_EQ(quantise(-2.5, 1.0), -3.0);
  EXPECT_EQ(quantise(0.375, 0.25), 0.5);
  EXPECT_EQ(quantise(1.234, 0.0), 1.234);  // ideal sensor
}

TEST(RateLimitedMove, MovesAtMostTheTravelAndStopsOnTheCommand) {
  EXPECT_DOUBLE_EQ(rate_limited_move(10.0, 20.0, 3.0), 13.0);
  EXPECT_DOUBLE_EQ(rate_limited_move(10.0, 0.0, 3.0), 7.0);
  EXPECT_DOUBLE_EQ(rate_limited_move(10.0, 11.0, 3.0), 11.0);
  EXPECT_DOUBLE_EQ(rate_limited_move(10.0, 20.0, std::numeric_limits<double>::infinity()), 20.0);
  // inf * 0 (an ideal actuator over an empty interval) is the ideal actuator too.
  EXPECT_DOUBLE_EQ(rate_limited_move(10.0, 20.0, std::numeric_limits<double>::infinity() * 0.0), 20.0);
}

TEST(FreeFlowLimitLevel, IsThePapersBorderAndItsLimits) {
  // 0.81 · 40 · (40 / 20)^0.72 by hand: 2^0.72 = 1.647182...
  EXPECT_NEAR(free_flow_limit_level(40.0, 20.0), 0.81 * 40.0 * 1.6471820345, 1e-8);
  // Homogeneous of degree one: millimetres and metres give the same border.
  EXPECT_NEAR(free_flow_limit_level(0.040, 0.020) * 1000.0, free_flow_limit_level(40.0, 20.0), 1e-9);
  EXPECT_TRUE(std::isinf(free_flow_limit_level(40.0, 0.0)));
  EXPECT_EQ(free_flow_limit_level(0.0, 20.0), 0.0);
}

}  // namespace
}  // namespace canalsim::laws
