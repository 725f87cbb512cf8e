// The realistic-truth helpers of testing/realistic.hpp do what they say (they are the "truth" of
// other tests, so they are checked against hand computations here).
#include "testing/realistic.hpp"

#include <cmath>

#include <gtest/gtest.h>

#include "gates/sluice_gate.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/design.hpp"

namespace canalsim::testing {
namespace {

Recording ramp_recording() {
  Recording r;
  std::vector<double> t, u, y;
  for (int k = 0; k < 200; ++k) {
    t.push_back(0.1 * k);
    u.push_back(k < 100 ? 30.0 : 35.0);
    y.push_back(50.0 + 0.5 * t.back());  // 0.5 mm/s
  }
  r.set_column(columns::time, t);
  r.set_column(columns::gate_command, u);
  r.set_column(columns::level_downstream_end, y);
  return r;
}

TEST(RealisticLevels, OffsetDriftAndTimeOffsetShiftALinearLevelByHand) {
  SensorRealism s;
  s.offset_mm = 0.7;
  s.drift_mm_per_s = 0.01;
  s.time_offset_s = -0.3;  // the levels lag the command by 0.3 s
  const Recording r = realistic_levels(ramp_recording(), s);
  const auto& y = r.column(columns::level_downstream_end);
  for (int k = 10; k < 190; ++k) {
    const double t = 0.1 * k;
    EXPECT_NEAR(y[static_cast<std::size_t>(k)], 50.0 + 0.5 * (t - 0.3) + 0.7 + 0.01 * t, 1e-9) << k;
  }
  EXPECT_EQ(r.column(columns::gate_command), ramp_recording().column(columns::gate_command));
}

TEST(RealisticLevels, QuantisationLatticeDoesNotPassThroughZero) {
  SensorRealism s;
  s.quantum_mm = 0.2;
  s.quantum_offset_mm = 0.07;
  const Recording r = realistic_levels(ramp_recording(), s);
  for (double y : r.column(columns::level_downstream_end)) {
    const double steps = (y - 0.07) / 0.2;
    EXPECT_NEAR(steps, std::round(steps), 1e-9);
  }
}

TEST(IndependentTruth, DiffersInGridLimiterCourantAndOptionallyGateLaw) {
  const auto lab = scenarios::builtin_scenario("lab");
  TruthVariation v;
  v.simple_gate_laws = true;
  const auto truth = independent_truth(lab, v);
  EXPECT_EQ(truth.pools.front().cells, 4 * lab.pools.front().cells);
  EXPECT_NE(truth.numerics.van_leer_limiter, lab.numerics.van_leer_limiter);
  EXPECT_EQ(truth.numerics.cfl, 0.45);
  ASSERT_TRUE(truth.head_gate.has_value());
  EXPECT_EQ(truth.head_gate->law, scenarios::GateLaw::simple);
  // Both gates pass the paper's eq. 9 with Cd = 0.6 in free flow and eq. 11 in submerged flow,
  // by hand: q = 0.6 a sqrt(2 g h) per unit width.
  const double a = 0.02, y1 = 0.06, y3 = 0.055, g = 9.81;
  for (const scenarios::GateSpec* gate : {&*truth.head_gate, &truth.downstream.gate}) {
    const gates::SluiceGate law(scenarios::gate_geometry(*gate).law);
    EXPECT_NEAR(law.discharge(y1, 0.0, a), 0.6 * a * std::sqrt(2.0 * g * y1), 1e-12);
    ASSERT_EQ(gates::classify_regime(y1, y3, a), gates::GateRegime::submerged);
    EXPECT_NEAR(law.discharge(y1, y3, a), 0.6 * a * std::sqrt(2.0 * g * (y1 - y3)), 1e-12);
  }
}

}  // namespace
}  // namespace canalsim::testing
