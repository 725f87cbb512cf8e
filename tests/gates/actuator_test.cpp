// Gate actuator (gates/actuator.*): ideal, and constant-speed motion of paper eq. (16).
#include "gates/actuator.hpp"

#include <cmath>
#include <gtest/gtest.h>
#include <stdexcept>

namespace canalsim::gates {
namespace {

ActuatorOptions rate_limited(double speed, double start) {
  ActuatorOptions options;
  options.mode = ActuatorMode::rate_limited;
  options.speed = speed;
  options.initial_position = start;
  return options;
}

TEST(GateActuator, IdealFollowsTheCommandAtOnce) {
  ActuatorOptions options;
  options.mode = ActuatorMode::ideal;
  GateActuator gate(options);
  EXPECT_EQ(gate.advance(0.01, 0.025), 0.025);
  EXPECT_EQ(gate.advance(0.0, 0.030), 0.030);
}

TEST(GateActuator, MovesAtExactlyTheRateAndStopsOnTheCommand) {
  // 10 mm/s from 20 mm to 30 mm: 1 s of travel, in 0.01 s steps.
  GateActuator gate(rate_limited(0.010, 0.020));
  const double dt = 0.01;
  for (int step = 1; step <= 100; ++step) {
    const double x = gate.advance(dt, 0.030);
    EXPECT_NEAR(x, 0.020 + 0.010 * dt * step, 1e-15) << step;
    EXPECT_NEAR(gate.last_velocity(), 0.010, 1e-12);
  }
  EXPECT_EQ(gate.position(), 0.030);  // lands exactly, no overshoot
  EXPECT_EQ(gate.advance(dt, 0.030), 0.030);
  EXPECT_EQ(gate.last_velocity(), 0.0);
}

TEST(GateActuator, ReachesTheCommandWithinAStepWithoutOvershoot) {
  GateActuator gate(rate_limited(0.010, 0.020));
  EXPECT_EQ(gate.advance(0.35, 0.0225), 0.0225);  // 2.5 mm needs 0.25 s < 0.35 s
  EXPECT_NEAR(gate.advance(0.1, 0.0), 0.0215, 1e-15);  // closing moves down at the same rate
}

TEST(GateActuator, ReversalTakesTheDistanceOverTheSpeed) {
  // A PRBS reversal of 10 mm at 10 mm/s takes 1 s.
  GateActuator gate(rate_limited(0.010, 0.030));
  double t = 0.0;
  while (gate.position() != 0.020) {
    gate.advance(0.001, 0.020);
    t += 0.001;
  }
  EXPECT_NEAR(t, 1.0, 1e-9);
}

TEST(GateActuator, ClampsCommandsToTheMechanicalRange) {
  ActuatorOptions options;
  options.mode = ActuatorMode::ideal;
  options.max_opening = 0.050;
  GateActuator gate(options);
  EXPECT_EQ(gate.advance(0.1, 0.080), 0.050);
  EXPECT_EQ(gate.advance(0.1, -0.010), 0.0);
  gate.reset(0.2);
  EXPECT_EQ(gate.position(), 0.050);
}

TEST(GateActuator, ValidationNamesTheField) {
  ActuatorOptions options;
  options.speed = 0.0;
  EXPECT_NE(options.validate().message().find("speed = 0: expected a gate speed in (0, 10] m/s"), std::string::npos);
  EXPECT_THROW(GateActuator{options}, std::invalid_argument);
  options = {};
  options.initial_position = 0.06;
  EXPECT_NE(options.validate().message().find("initial_position"), std::string::npos);
  GateActuator gate;
  EXPECT_THROW(gate.advance(-1.0, 0.01), std::invalid_argument);
}

}  // namespace
}  // namespace canalsim::gates
