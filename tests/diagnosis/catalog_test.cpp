// The catalog: names of issue 5, parameter mappings, and what each effect changes.
#include "diagnosis/catalog.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "scenarios/builtin.hpp"

namespace canalsim::diagnosis {
namespace {

TEST(Catalog, HoldsTheNineEffectsOfTheIssueByName) {
  const char* names[] = {"gate_rate_limit", "sensor_quantization", "sensor_delay", "sensor_offset", "gate_leakage",
                         "discharge_coefficient", "friction", "lateral_outflow", "downstream_gate"};
  EXPECT_EQ(catalog().size(), 9u);
  for (const char* n : names) {
    const auto e = effect_from_name(n);
    ASSERT_TRUE(e) << n;
    EXPECT_STREQ(info(*e).name, n);
  }
  EXPECT_FALSE(effect_from_name("wave_resonance"));
}

TEST(Catalog, ParameterAndSearchCoordinateAreInverse) {
  for (const auto& e : catalog()) {
    for (double f : {0.2, 0.5, 0.9}) {
      const double theta = e.theta_low + f * (e.theta_high - e.theta_low);
      EXPECT_NEAR(to_theta(e.effect, to_parameter(e.effect, theta)), theta, 1e-12) << e.name;
    }
  }
  EXPECT_TRUE(std::isinf(no_effect_parameter(Effect::gate_rate_limit)));
  EXPECT_DOUBLE_EQ(no_effect_parameter(Effect::friction), 1.0);
}

TEST(Catalog, MaterialityIsHalfTheSmallestMagnitudeOfInterest) {
  EXPECT_TRUE(is_material(Effect::gate_rate_limit, 20.0));
  EXPECT_FALSE(is_material(Effect::gate_rate_limit, 150.0));
  EXPECT_TRUE(is_material(Effect::friction, 0.5));
  EXPECT_FALSE(is_material(Effect::friction, 1.1));
  EXPECT_TRUE(is_material(Effect::sensor_offset, -0.5));
  EXPECT_FALSE(is_material(Effect::discharge_coefficient, 1.01));
}

TEST(Catalog, HydraulicEffectsChangeTheScenarioFields) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  scenarios::Scenario s = lab;
  apply_effect(Effect::gate_rate_limit, 10.0, s, 0.0);
  EXPECT_DOUBLE_EQ(s.head_gate->actuator_speed_m_s, 0.010);
  apply_effect(Effect::gate_leakage, 2.0, s, 0.0);
  EXPECT_NEAR(s.head_gate->leakage_m, lab.head_gate->leakage_m + 0.002, 1e-15);
  apply_effect(Effect::discharge_coefficient, 0.9, s, 0.0);
  EXPECT_NEAR(s.head_gate->discharge_coefficient, 0.9 * lab.head_gate->discharge_coefficient, 1e-15);
  apply_effect(Effect::friction, 2.0, s, 0.0);
  EXPECT_NEAR(s.pools[0].manning_n, 2.0 * lab.pools[0].manning_n, 1e-15);
  apply_effect(Effect::lateral_outflow, 0.1, s, 5e-4);
  ASSERT_EQ(s.pools[0].offtakes.size(), lab.pools[0].offtakes.size() + 1);
  EXPECT_NEAR(s.pools[0].offtakes.back().discharge_m3s, 5e-5, 1e-15);
  apply_effect(Effect::downstream_gate, -1.0, s, 0.0);
  EXPECT_NEAR(s.downstream.gate.opening_m, lab.downstream.gate.opening_m - 0.001, 1e-15);
}

TEST(Catalog, SensorEffectsChangeTheSensorModelOnly) {
  SensorModel m{0.05, 0.0, 0.0};
  apply_effect(Effect::sensor_delay, 0.5, m);
  apply_effect(Effect::sensor_offset, -1.0, m);
  apply_effect(Effect::sensor_quantization, 0.4, m);
  EXPECT_DOUBLE_EQ(m.delay_s, 0.5);
  EXPECT_DOUBLE_EQ(m.offset_mm, -1.0);
  EXPECT_DOUBLE_EQ(m.resolution_mm, 0.4);
  EXPECT_THROW(apply_effect(Effect::friction, 2.0, m), std::invalid_argument);
}

TEST(Catalog, EffectsAScenarioCannotCarryAreNamed) {
  scenarios::Scenario s = scenarios::builtin_scenario("lab");
  s.head_gate.reset();
  EXPECT_NE(unsupported_reason(Effect::gate_leakage, s).find("head gate"), std::string::npos);
  EXPECT_THROW(apply_effect(Effect::gate_leakage, 1.0, s, 0.0), std::invalid_argument);
  s.downstream.kind = scenarios::DownstreamKind::weir;
  EXPECT_FALSE(unsupported_reason(Effect::downstream_gate, s).empty());
}

TEST(ExpectedReading, IsRoundingWithoutSpreadAndTheLevelItselfForALargeSpread) {
  EXPECT_DOUBLE_EQ(expected_reading(0.74, 0.5, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(expected_reading(0.76, 0.5, 0.0), 1.0);
  EXPECT_NEAR(expected_reading(0.63, 0.5, 2.0), 0.63, 1e-9);
  // Symmetric about a lattice point and about the midpoint between two.
  EXPECT_NEAR(expected_reading(1.0, 0.5, 0.1), 1.0, 1e-12);
  EXPECT_NEAR(expected_reading(1.25, 0.5, 0.1), 1.25, 1e-12);
}

// Monte Carlo: for a model that is off by a Gaussian error of spread σ, the expected reading
// predicts the quantised readings better in mean square than either rounding the model level or
// the level itself (the property the diagnosis relies on for sensor_quantization).
TEST(ExpectedReading, PredictsQuantisedReadingsBetterThanRoundingOrTheRawLevel) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> level(40.0, 60.0);
  for (double sigma : {0.05, 0.15, 0.3}) {
    std::normal_distribution<double> error(0.0, sigma);
    const double r = 0.5;
    double se_expected = 0.0, se_round = 0.0, se_raw = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const double model = level(rng);
      const double reading = r * std::round((model + error(rng)) / r);
      se_expected += std::pow(reading - expected_reading(model, r, sigma), 2);
      se_round += std::pow(reading - r * std::round(model / r), 2);
      se_raw += std::pow(reading - model, 2);
    }
    EXPECT_LT(se_expected, se_round) << "sigma " << sigma;
    EXPECT_LT(se_expected, se_raw) << "sigma " << sigma;
  }
}

}  // namespace
}  // namespace canalsim::diagnosis
