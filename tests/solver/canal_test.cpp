// Canal (solver/canal.*): time stepping driver, multi-reach links, volume accounting, sampling and
// failure reporting.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "solver/canal.hpp"

namespace canalsim::solver {
namespace {

constexpr double g = 9.81;

ReachSpec reach(double length, int cells, Section section, double depth, double discharge = 0.0) {
  ReachSpec spec;
  spec.length = length;
  spec.cells = cells;
  spec.section = section;
  spec.initial_depth.assign(static_cast<std::size_t>(cells), depth);
  spec.initial_discharge.assign(static_cast<std::size_t>(cells), discharge);
  return spec;
}

// Records what the solver reports through the step hook.
class RecordingInflow final : public Boundary {
 public:
  explicit RecordingInflow(double q) : q_(q) {}
  Flux flux(const BoundaryInput& in) const override {
    return FixedDischargeBoundary::constant(q_ * (1.0 + 0.5 * std::sin(in.time)))->flux(in);
  }
  void on_step_accepted(double, double dt, double face_discharge) override { volume += dt * face_discharge; ++steps; }
  double volume = 0.0;
  long steps = 0;

 private:
  double q_;
};

TEST(VolumeBalance, ClosesToRoundOffWithInflowOutflowAndLateralFlow) {
  ReachSpec spec = reach(5.0, 100, {0.08, 0.0}, 0.06, 0.001);
  spec.manning_n = 0.01;
  for (int i = 0; i < 100; ++i) spec.bed_elevation.push_back(0.002 * (100 - i) / 100.0);
  Canal canal;
  ASSERT_TRUE(canal.add_reach(spec));
  auto inflow = std::make_shared<RecordingInflow>(0.0015);
  canal.set_boundary(0, End::upstream, inflow);
  canal.set_boundary(0, End::downstream, std::make_shared<CriticalDepthBoundary>());
  auto& ql = canal.reach(0).lateral_inflow();
  for (int i = 20; i < 30; ++i) ql[static_cast<std::size_t>(i)] = 2e-4;   // inflow over 0.5 m
  for (int i = 60; i < 70; ++i) ql[static_cast<std::size_t>(i)] = -1e-4;  // withdrawal
  ASSERT_TRUE(canal.advance_to(20.0));
  const VolumeBalance b = canal.balance(0);
  EXPECT_GT(b.inflow, 0.0);
  EXPECT_GT(b.outflow, 0.0);
  EXPECT_NEAR(b.lateral, 20.0 * (10 * 0.05 * 2e-4 - 10 * 0.05 * 1e-4), 1e-12);
  EXPECT_LT(b.relative_error(), 1e-12) << "error " << b.error() << " m3";
  // The hook saw exactly the volume the accounting booked.
  EXPECT_NEAR(inflow->volume, b.inflow, 1e-15);
  EXPECT_EQ(inflow->steps, canal.statistics().steps);
  const VolumeBalance t = canal.total_balance();
  EXPECT_DOUBLE_EQ(t.error(), b.error());
}

TEST(VolumeBalance, InflowIntoADrySlopingTrapezoidalChannelWetsItAndBalanceCloses) {
  ReachSpec spec = reach(20.0, 80, {0.5, 1.0}, 0.0);
  spec.manning_n = 0.02;
  for (int i = 0; i < 80; ++i) spec.bed_elevation.push_back(0.01 * (80 - i) * 0.25);
  Canal canal;
  ASSERT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(0.05));
  canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  ASSERT_TRUE(canal.advance_to(30.0));
  for (double a : canal.reach(0).area()) EXPECT_GE(a, 0.0);
  EXPECT_GT(canal.sample(0, 10.0, Quantity::depth), 0.0);  // the front passed mid-reach
  const VolumeBalance b = canal.balance(0);
  EXPECT_NEAR(b.inflow, 0.05 * 30.0, 1e-12);
  EXPECT_LT(b.relative_error(), 1e-12) << b.error();
}

TEST(VolumeBalance, ResetStartsFromTheCurrentStorage) {
  Canal canal;
  ASSERT_TRUE(canal.add_reach(reach(10.0, 20, {1.0, 0.0}, 0.5)));
  canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(0.1));
  canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  ASSERT_TRUE(canal.advance_to(5.0));
  canal.reset_balance();
  const VolumeBalance b = canal.balance(0);
  EXPECT_EQ(b.inflow, 0.0);
  EXPECT_EQ(b.storage_change(), 0.0);
}

TEST(AdvanceTo, LandsExactlyOnTheEndTime) {
  Canal canal;
  ASSERT_TRUE(canal.add_reach(reach(5.0, 100, {0.08, 0.0}, 0.06, 0.0005)));
  canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(0.001));
  canal.set_boundary(0, End::downstream, std::make_shared<CriticalDepthBoundary>());
  for (double t : {0.1, 0.237, 3.0}) {
    ASSERT_TRUE(canal.advance_to(t));
    EXPECT_EQ(canal.time(), t);
  }
}

TEST(Sample, InterpolatesLinearlyBetweenCellCentres) {
  ReachSpec spec = reach(1.0, 4, {1.0, 0.0}, 0.0);
  spec.initial_depth = {1.0, 2.0, 3.0, 4.0};
  spec.initial_discharge = {0.5, 1.0, 1.5, 2.0};
  Canal canal;
  ASSERT_TRUE(canal.add_reach(spec));
  EXPECT_DOUBLE_EQ(canal.sample(0, 0.25, Quantity::depth), 1.5);       // between centres 0.125, 0.375
  EXPECT_DOUBLE_EQ(canal.sample(0, 0.0, Quantity::depth), 1.0);        // constant before the first centre
  EXPECT_DOUBLE_EQ(canal.sample(0, 1.0, Quantity::level), 4.0);
  EXPECT_DOUBLE_EQ(canal.sample(0, 0.375, Quantity::velocity), 0.5);
  EXPECT_DOUBLE_EQ(canal.sample(0, 0.625, Quantity::area), 3.0);
  EXPECT_NEAR(canal.sample(0, 0.125, Quantity::froude), 0.5 / std::sqrt(g), 1e-15);
}

TEST(MultiReach, TwoLinkedReachesAtRestOverABedStepStayAtRestAndConserveVolume) {
  Canal canal;
  ReachSpec up = reach(5.0, 50, {1.0, 0.0}, 0.4);
  up.bed_elevation.assign(50, 0.3);
  ReachSpec down = reach(5.0, 50, {0.8, 0.5}, 0.7);
  ASSERT_TRUE(canal.add_reach(up));
  ASSERT_TRUE(canal.add_reach(down));
  ASSERT_TRUE(canal.connect(0, 1, std::make_shared<ContinuousLink>()));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(1, End::downstream, std::make_shared<WallBoundary>());
  for (int s = 0; s < 200; ++s) ASSERT_TRUE(canal.step());
  for (int r = 0; r < 2; ++r)
    for (double q : canal.reach(r).discharge()) EXPECT_LT(std::abs(q), 1e-12);
}

TEST(MultiReach, WaveThroughALinkConservesTotalVolume) {
  Canal canal;
  ReachSpec up = reach(5.0, 50, {1.0, 0.0}, 0.4);
  for (int i = 25; i < 50; ++i) up.initial_depth[static_cast<std::size_t>(i)] = 0.6;  // a dam break at the middle
  ASSERT_TRUE(canal.add_reach(up));
  ASSERT_TRUE(canal.add_reach(reach(3.0, 30, {1.0, 0.0}, 0.4)));
  ASSERT_TRUE(canal.connect(0, 1, std::make_shared<ContinuousLink>()));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(1, End::downstream, std::make_shared<WallBoundary>());
  const double v0 = canal.reach(0).volume() + canal.reach(1).volume();
  ASSERT_TRUE(canal.advance_to(5.0));
  EXPECT_GT(canal.balance(1).inflow, 0.0);  // water crossed the link
  EXPECT_NEAR(canal.balance(0).outflow, canal.balance(1).inflow, 1e-15);
  EXPECT_LT(std::abs(canal.reach(0).volume() + canal.reach(1).volume() - v0) / v0, 1e-13);
  EXPECT_LT(canal.total_balance().relative_error(), 1e-13);
}

TEST(CheckReady, AnOpenEndIsReportedWithTheReachName) {
  Canal canal;
  ReachSpec spec = reach(5.0, 10, {0.08, 0.0}, 0.06);
  spec.name = "main pool";
  ASSERT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  const Status st = canal.advance_to(1.0);
  EXPECT_FALSE(st);
  EXPECT_NE(st.message().find("downstream end of reach 0 (main pool)"), std::string::npos) << st.message();
}

// A boundary that injects NaN after t = 0.5 s.
class FailingBoundary final : public Boundary {
 public:
  Flux flux(const BoundaryInput& in) const override {
    return in.time > 0.5 ? Flux{std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0} : WallBoundary().flux(in);
  }
};

TEST(Failure, NonFiniteStateStopsTheRunWithTimeReachAndCell) {
  Canal canal;
  ASSERT_TRUE(canal.add_reach(reach(5.0, 10, {0.08, 0.0}, 0.06)));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<FailingBoundary>());
  const Status st = canal.advance_to(2.0);
  ASSERT_FALSE(st);
  EXPECT_EQ(st.reach(), 0);
  EXPECT_EQ(st.cell(), 9);
  EXPECT_GT(st.time(), 0.5);
  EXPECT_NE(st.message().find("non-finite"), std::string::npos);
  EXPECT_NE(st.message().find("cell 9"), std::string::npos);
  for (double a : canal.reach(0).area()) EXPECT_TRUE(std::isfinite(a));  // left at the last good state
}

TEST(Failure, NanWrittenIntoTheStateIsRejectedBeforeStepping) {
  Canal canal;
  ASSERT_TRUE(canal.add_reach(reach(5.0, 10, {0.08, 0.0}, 0.06)));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  canal.reach(0).discharge()[4] = std::nan("");
  const Status st = canal.advance_to(1.0);
  ASSERT_FALSE(st);
  EXPECT_EQ(st.cell(), 4);
}

TEST(Failure, AnAllDryStillCanalWithoutATimeLimitReportsAnUnboundedStep) {
  Canal canal;
  ASSERT_TRUE(canal.add_reach(reach(5.0, 10, {0.08, 0.0}, 0.0)));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  EXPECT_FALSE(canal.step());
  EXPECT_TRUE(canal.advance_to(1.0));  // with an end time the step is bounded
}

TEST(FirstOrder, DamBreakRunsAndConservesVolume) {
  SolverOptions o;
  o.order = SpatialOrder::first;
  o.cfl = 0.9;
  Canal canal(o);
  ReachSpec spec = reach(10.0, 100, {1.0, 0.0}, 0.5);
  for (int i = 0; i < 50; ++i) spec.initial_depth[static_cast<std::size_t>(i)] = 1.0;
  ASSERT_TRUE(canal.add_reach(spec));
  canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  const double v0 = canal.reach(0).volume();
  ASSERT_TRUE(canal.advance_to(2.0));
  EXPECT_LT(std::abs(canal.reach(0).volume() - v0) / v0, 1e-13);
}

}  // namespace
}  // namespace canalsim::solver
