// The catalog: names, per-channel rows, parameter mappings, and what each effect changes.
#include "diagnosis/catalog.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/recording.hpp"
#include "scenarios/builtin.hpp"

namespace canalsim::diagnosis {
namespace {

Effect named(const std::string& name) {
  const auto e = effect_from_name(name);
  if (!e) throw std::invalid_argument("no effect " + name);
  return *e;
}

TEST(Catalog, NamesAnEffectByItsRowAndForInstrumentsItsChannel) {
  EXPECT_EQ(named("gate_leakage").name(), "gate_leakage");
  EXPECT_EQ(named("sensor_offset[y_dwe_mm]").channel, "y_dwe_mm");
  EXPECT_EQ(named("sensor_offset[y_dwe_mm]").name(), "sensor_offset[y_dwe_mm]");
  EXPECT_EQ(named("sensor_delay[y_check2_mm]").channel, "y_check2_mm");
  EXPECT_FALSE(effect_from_name("wave_resonance"));
  EXPECT_FALSE(effect_from_name("sensor_offset"));          // a per-channel row needs its channel
  EXPECT_FALSE(effect_from_name("gate_leakage[y_up_mm]"));  // a canal row has none
  EXPECT_FALSE(effect_from_name("sensor_offset[q_lps]"));   // a flow is not a level
  EXPECT_FALSE(effect_from_name("sensor_offset[y_up_mm"));
  EXPECT_NE(catalog_names().find("sensor_offset[CHANNEL]"), std::string::npos);
}

TEST(Catalog, ExpandsPerChannelRowsOverTheRecordedLevels) {
  const auto names_of = [](const std::vector<Effect>& effects) {
    std::vector<std::string> out;
    for (const auto& e : effects) out.push_back(e.name());
    return out;
  };
  const auto three = names_of(effects_for({"y_up_mm", "y_dw_mm", "y_dwe_mm"}));
  const auto one = names_of(effects_for({"y_dwe_mm"}));
  std::size_t per_channel = 0, common = 0;
  for (const auto& k : catalog()) {
    per_channel += k.scope == Scope::each_level_channel;
    common += k.scope == Scope::every_level_channel;
  }
  EXPECT_EQ(three.size(), catalog().size() + 2 * per_channel);
  // One level channel: no common cause to tell from a fault of that sensor.
  EXPECT_EQ(one.size(), catalog().size() - common);
  for (const char* n : {"sensor_offset[y_up_mm]", "sensor_drift[y_dw_mm]", "sensor_scale[y_dwe_mm]", "level_datum",
                        "command_delay", "command_offset", "gate_leakage"}) {
    EXPECT_NE(std::find(three.begin(), three.end(), n), three.end()) << n;
  }
  EXPECT_EQ(std::find(one.begin(), one.end(), "level_datum"), one.end());
}

TEST(Catalog, EveryRowCarriesTheEditOfWhatItActsOn) {
  for (const auto& k : catalog()) {
    EXPECT_EQ(k.edit_scenario != nullptr, k.acts == Acts::hydraulics) << k.name;
    EXPECT_EQ(k.gate_saw != nullptr, k.acts == Acts::command) << k.name;
    EXPECT_EQ(k.edit_sensors != nullptr, k.acts == Acts::readings) << k.name;
    EXPECT_LT(k.theta_low, k.theta_high) << k.name;
    EXPECT_GE(k.theta_none, k.theta_low) << k.name;
    EXPECT_LE(k.theta_none, k.theta_high) << k.name;
    // A drawn magnitude is material and inside the search range.
    EXPECT_GE(k.draw.low, k.material) << k.name;
    EXPECT_LE(k.theta_none + k.draw.high, k.theta_high) << k.name;
    if (k.draw.either_sign) {
      EXPECT_GE(k.theta_none - k.draw.high, k.theta_low) << k.name;
    }
    if (k.twin_without_gate_position) {
      EXPECT_NE(kind_named(k.twin_without_gate_position), nullptr) << k.name;
    }
    if (k.spanned_by) {
      EXPECT_NE(kind_named(k.spanned_by), nullptr) << k.name;
    }
  }
}

TEST(Catalog, ParameterAndSearchCoordinateAreInverse) {
  for (const auto& k : catalog()) {
    const Effect e{&k, k.scope == Scope::each_level_channel ? "y_dwe_mm" : ""};
    for (double f : {0.2, 0.5, 0.9}) {
      const double theta = k.theta_low + f * (k.theta_high - k.theta_low);
      EXPECT_NEAR(to_theta(e, to_parameter(e, theta)), theta, 1e-12) << k.name;
    }
  }
  EXPECT_TRUE(std::isinf(no_effect_parameter(named("gate_rate_limit"))));
  EXPECT_DOUBLE_EQ(no_effect_parameter(named("friction")), 1.0);
  EXPECT_DOUBLE_EQ(no_effect_parameter(named("sensor_scale[y_up_mm]")), 1.0);
}

TEST(Catalog, MaterialityIsHalfTheSmallestMagnitudeOfInterest) {
  EXPECT_TRUE(is_material(named("gate_rate_limit"), 20.0));
  EXPECT_FALSE(is_material(named("gate_rate_limit"), 150.0));
  EXPECT_TRUE(is_material(named("friction"), 0.5));
  EXPECT_FALSE(is_material(named("friction"), 1.1));
  EXPECT_TRUE(is_material(named("sensor_offset[y_dwe_mm]"), -0.5));
  EXPECT_FALSE(is_material(named("discharge_coefficient"), 1.01));
  EXPECT_TRUE(is_material(named("sensor_scale[y_dw_mm]"), 0.97));
}

TEST(Catalog, HydraulicEffectsChangeTheScenarioFields) {
  const scenarios::Scenario lab = scenarios::builtin_scenario("lab");
  scenarios::Scenario s = lab;
  apply_effect(named("gate_rate_limit"), 10.0, s, 0.0);
  EXPECT_DOUBLE_EQ(s.head_gate->actuator_speed_m_s, 0.010);
  apply_effect(named("gate_leakage"), 2.0, s, 0.0);
  EXPECT_NEAR(s.head_gate->leakage_m, lab.head_gate->leakage_m + 0.002, 1e-15);
  apply_effect(named("discharge_coefficient"), 0.9, s, 0.0);
  EXPECT_NEAR(s.head_gate->discharge_coefficient, 0.9 * lab.head_gate->discharge_coefficient, 1e-15);
  apply_effect(named("friction"), 2.0, s, 0.0);
  EXPECT_NEAR(s.pools[0].manning_n, 2.0 * lab.pools[0].manning_n, 1e-15);
  apply_effect(named("lateral_outflow"), 0.1, s, 5e-4);
  ASSERT_EQ(s.pools[0].offtakes.size(), lab.pools[0].offtakes.size() + 1);
  EXPECT_NEAR(s.pools[0].offtakes.back().discharge_m3s, 5e-5, 1e-15);
  apply_effect(named("downstream_gate"), -1.0, s, 0.0);
  EXPECT_NEAR(s.downstream.gate.opening_m, lab.downstream.gate.opening_m - 0.001, 1e-15);
  EXPECT_THROW(apply_effect(named("sensor_offset[y_up_mm]"), 1.0, s, 0.0), std::invalid_argument);
}

TEST(Catalog, InstrumentEffectsChangeOneSensorOfTheModel) {
  SensorModel m{0.05, 0.0, 0.0};
  apply_effect(named("sensor_delay[y_dwe_mm]"), 0.5, m);
  apply_effect(named("sensor_offset[y_up_mm]"), -1.0, m);
  apply_effect(named("sensor_quantization[y_dw_mm]"), 0.4, m);
  apply_effect(named("sensor_drift[y_up_mm]"), 0.3, m);
  apply_effect(named("sensor_scale[y_dwe_mm]"), 1.02, m);
  apply_effect(named("level_datum"), 0.7, m);
  apply_effect(named("command_delay"), 0.2, m);
  EXPECT_DOUBLE_EQ(m.channel_fault.at("y_dwe_mm").delay_s, 0.5);
  EXPECT_DOUBLE_EQ(m.channel_fault.at("y_dwe_mm").gain, 1.02);
  EXPECT_DOUBLE_EQ(m.channel_fault.at("y_up_mm").offset_mm, -1.0);
  EXPECT_DOUBLE_EQ(m.channel_fault.at("y_up_mm").drift_mm_per_min, 0.3);
  EXPECT_DOUBLE_EQ(m.channel_fault.at("y_dw_mm").resolution_mm, 0.4);
  EXPECT_DOUBLE_EQ(m.offset_mm, 0.7);
  EXPECT_DOUBLE_EQ(m.clock_delay_s, 0.2);
  EXPECT_DOUBLE_EQ(m.delay_s, 0.0);
  EXPECT_THROW(apply_effect(named("friction"), 2.0, m), std::invalid_argument);
}

// What the model reads with one sensor's faults, against the closed form of each fault on a
// ramp (a level linear in time, on which linear interpolation of a delay is exact).
TEST(Catalog, AFaultySensorReadsTheClosedFormOfItsFaultsAndTheOthersReadTrue) {
  const double period = 0.1;
  calibration::Channels truth;
  std::vector<double> ramp(200), flat(200, 30.0);
  for (std::size_t k = 0; k < ramp.size(); ++k) ramp[k] = 50.0 + 0.2 * static_cast<double>(k);
  truth["y_dwe_mm"] = ramp;
  truth["y_up_mm"] = flat;
  truth["q_lps"] = ramp;
  SensorModel m;
  apply_effect(named("sensor_offset[y_dwe_mm]"), -1.5, m);
  apply_effect(named("sensor_delay[y_dwe_mm]"), 0.5, m);
  apply_effect(named("sensor_drift[y_dwe_mm]"), 0.6, m);
  apply_effect(named("sensor_scale[y_dwe_mm]"), 1.03, m);
  const calibration::Channels read = calibration::observe(truth, m, period);
  for (std::size_t k = 10; k < ramp.size(); ++k) {
    const double t = static_cast<double>(k) * period;
    const double level = 50.0 + 2.0 * (t - 0.5);  // 0.2 mm per 0.1 s sample, 0.5 s late
    EXPECT_NEAR(read.at("y_dwe_mm")[k], 1.03 * level - 1.5 + 0.6 * t / 60.0, 1e-9) << k;
    EXPECT_DOUBLE_EQ(read.at("y_up_mm")[k], 30.0);
    EXPECT_DOUBLE_EQ(read.at("q_lps")[k], ramp[k]);
  }
  // The clock shifts every channel, the flow too.
  SensorModel late;
  apply_effect(named("command_delay"), 0.3, late);
  const calibration::Channels shifted = calibration::observe(truth, late, period);
  EXPECT_NEAR(shifted.at("q_lps")[50], ramp[47], 1e-9);
  EXPECT_NEAR(shifted.at("y_dwe_mm")[50], ramp[47], 1e-9);
}

TEST(Catalog, AQuantisedSensorReadsOnItsOwnOffsetLattice) {
  calibration::Channels truth;
  truth["y_dw_mm"] = {40.00, 40.12, 40.31, 40.52, 40.66};
  SensorModel m;
  m.channel_fault["y_dw_mm"].resolution_mm = 0.25;
  m.channel_fault["y_dw_mm"].lattice_offset_mm = 0.1;
  const auto read = calibration::observe(truth, m, 0.13).at("y_dw_mm");
  const double expected[] = {40.1, 40.1, 40.35, 40.6, 40.6};  // nearest of 0.1 + 0.25 k
  for (std::size_t k = 0; k < read.size(); ++k) EXPECT_NEAR(read[k], expected[k], 1e-9) << k;
}

TEST(Catalog, CommandEffectsGiveTheOpeningTheGateHad) {
  calibration::Replay replay;
  replay.operating_point_mm = 20.0;
  replay.drive.set_column(columns::time, {-0.001, 0.0, 60.0, 120.0});
  replay.drive.set_column(columns::gate_command, {20.0, 25.0, 15.0, 25.0});
  calibration::Replay offset = replay, gain = replay, drift = replay;
  apply_effect(named("command_offset"), 2.0, offset);   // the logger reads 2 mm high
  apply_effect(named("command_scale"), 1.25, gain);     // the logger reads 1.25 x the opening
  apply_effect(named("command_drift"), 1.0, drift);     // 1 mm/min high, growing
  EXPECT_DOUBLE_EQ(offset.operating_point_mm, 18.0);
  EXPECT_DOUBLE_EQ(offset.drive.column(columns::gate_command)[2], 13.0);
  EXPECT_DOUBLE_EQ(gain.drive.column(columns::gate_command)[1], 20.0);
  EXPECT_DOUBLE_EQ(gain.operating_point_mm, 16.0);
  EXPECT_DOUBLE_EQ(drift.drive.column(columns::gate_command)[3], 23.0);
  EXPECT_DOUBLE_EQ(drift.drive.column(columns::gate_command)[0], 20.0);
  EXPECT_THROW(apply_effect(named("gate_leakage"), 1.0, offset), std::invalid_argument);
}

TEST(Catalog, EffectsAScenarioCannotCarryAreNamed) {
  scenarios::Scenario s = scenarios::builtin_scenario("lab");
  s.head_gate.reset();
  EXPECT_NE(unsupported_reason(named("gate_leakage"), s).find("head gate"), std::string::npos);
  EXPECT_THROW(apply_effect(named("gate_leakage"), 1.0, s, 0.0), std::invalid_argument);
  s.downstream.kind = scenarios::DownstreamKind::weir;
  EXPECT_FALSE(unsupported_reason(named("downstream_gate"), s).empty());
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
