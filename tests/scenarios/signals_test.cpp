// Input signals (scenarios/signals.*): constant, step, ramp, and series replayed from a recording.
#include "scenarios/signals.hpp"

#include <gtest/gtest.h>
#include <memory>
#include <stdexcept>
#include <vector>

namespace canalsim {
namespace {

TEST(StepSignal, JumpsAtTheStartTime) {
  const StepSignal step(0.025, 0.005, 10.0);
  EXPECT_EQ(step.value(0.0), 0.025);
  EXPECT_EQ(step.value(9.999), 0.025);
  EXPECT_DOUBLE_EQ(step.value(10.0), 0.030);
  EXPECT_DOUBLE_EQ(step(1e6), 0.030);
}

TEST(StepSignal, JumpsOnceAtItsStartWhenItChanges) {
  EXPECT_EQ(StepSignal(0.025, 0.005, 10.0).jumps(0.0, 20.0), std::vector<double>{10.0});
  EXPECT_TRUE(StepSignal(0.025, 0.005, 10.0).jumps(10.0, 20.0).empty());  // (from, to]
  EXPECT_TRUE(StepSignal(0.025, 0.0, 10.0).jumps(0.0, 20.0).empty());
}

TEST(RampSignal, RisesLinearlyThenHolds) {
  const RampSignal ramp(0.025, 0.010, 10.0, 20.0);
  EXPECT_EQ(ramp.value(5.0), 0.025);
  EXPECT_NEAR(ramp.value(15.0), 0.0275, 1e-16);
  EXPECT_NEAR(ramp.value(20.0), 0.030, 1e-16);
  EXPECT_DOUBLE_EQ(ramp.value(30.0), 0.035);
  EXPECT_DOUBLE_EQ(ramp.value(100.0), 0.035);
  EXPECT_THROW(RampSignal(0.0, 1.0, 0.0, 0.0), std::invalid_argument);
}

TEST(SignalInterface, CallsThroughTheBaseClass) {
  const std::vector<SignalPtr> signals = {std::make_shared<ConstantSignal>(0.02),
                                          std::make_shared<StepSignal>(0.0, 1.0, 1.0)};
  EXPECT_EQ(signals[0]->value(3.0), 0.02);
  EXPECT_EQ(signals[1]->value(3.0), 1.0);
}

TEST(SeriesSignal, InterpolatesLinearlyBetweenSamples) {
  const SeriesSignal series({0.0, 1.0, 3.0}, {10.0, 20.0, 0.0});
  EXPECT_EQ(series.value(0.0), 10.0);
  EXPECT_NEAR(series.value(0.25), 12.5, 1e-14);
  EXPECT_NEAR(series.value(2.0), 10.0, 1e-14);
  EXPECT_EQ(series.value(3.0), 0.0);
}

TEST(SeriesSignal, ZeroOrderHoldKeepsTheLatestSample) {
  const SeriesSignal series({0.0, 1.0, 3.0}, {10.0, 20.0, 0.0}, Interpolation::zero_order_hold);
  EXPECT_EQ(series.value(0.999), 10.0);
  EXPECT_EQ(series.value(1.0), 20.0);
  EXPECT_EQ(series.value(2.999), 20.0);
  EXPECT_EQ(series.value(3.0), 0.0);
}

TEST(SeriesSignal, JumpsWhereTheHeldValueChangesAndNowhereWhenInterpolated) {
  const std::vector<double> t{0.0, 1.0, 2.0, 3.0}, v{10.0, 20.0, 20.0, 0.0};
  EXPECT_EQ(SeriesSignal(t, v, Interpolation::zero_order_hold).jumps(-1.0, 5.0), (std::vector<double>{1.0, 3.0}));
  EXPECT_EQ(SeriesSignal(t, v, Interpolation::zero_order_hold).jumps(1.0, 2.5), std::vector<double>{});
  EXPECT_TRUE(SeriesSignal(t, v).jumps(-1.0, 5.0).empty());
}

TEST(SeriesSignal, HoldsTheEndValuesOutsideTheRecord) {
  const SeriesSignal series({1.0, 2.0}, {5.0, 7.0});
  EXPECT_EQ(series.value(-10.0), 5.0);
  EXPECT_EQ(series.value(10.0), 7.0);
}

TEST(SeriesSignal, RejectsUnorderedOrMismatchedSamples) {
  EXPECT_THROW(SeriesSignal({0.0, 0.0}, {1.0, 2.0}), std::invalid_argument);
  EXPECT_THROW(SeriesSignal({0.0, 1.0}, {1.0}), std::invalid_argument);
  EXPECT_THROW(SeriesSignal({}, {}), std::invalid_argument);
}

TEST(SeriesSignal, ReplaysARecordingColumnInSiUnits) {
  const Recording rec = parse_recording(
      "t_s,u_mm,y_dwe_mm,q_lps\n0,25,50,1.5\n0.13,30,51,1.6\n0.26,20,52,1.7\n", "input.csv");
  const auto u = SeriesSignal::from_recording(rec, "u_mm", Interpolation::zero_order_hold);
  EXPECT_NEAR(u.value(0.2), 0.030, 1e-15);
  const auto q = SeriesSignal::from_recording(rec, "q_lps");
  EXPECT_NEAR(q.value(0.065), 1.55e-3, 1e-15);
  EXPECT_THROW(SeriesSignal::from_recording(rec, "x_up_mm"), InputError);
}

TEST(SiScaleOfColumn, ReadsTheUnitSuffix) {
  EXPECT_EQ(si_scale_of_column("y_dwe_mm"), 1e-3);
  EXPECT_EQ(si_scale_of_column("q_lps"), 1e-3);
  EXPECT_EQ(si_scale_of_column("t_s"), 1.0);
}

}  // namespace
}  // namespace canalsim
