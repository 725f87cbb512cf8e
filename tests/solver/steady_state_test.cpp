// Steady state by Newton (KINSOL + KLU): the state long time marching converges to, reached in a
// few dozen residual evaluations; failure is a returned status that leaves the state untouched.
#include "solver/steady_state.hpp"

#include <cmath>
#include <gtest/gtest.h>

#include "solver/boundary.hpp"
#include "testing/reaches.hpp"

namespace canalsim::solver {
namespace {

// Goutal & Maurel's subcritical bump (q = 4.42 m²/s, h_out = 2 m) with Manning friction, so that
// both the bed and friction shape the profile.
ReachSpec bump_channel(int cells, double length = 25.0) {
  ReachSpec spec;
  spec.length = length;
  spec.cells = cells;
  spec.section = {1.0, 0.0};
  spec.manning_n = 0.03;
  for (int i = 0; i < cells; ++i) {
    const double x = (i + 0.5) * length / cells;
    spec.bed_elevation.push_back(x > 8.0 && x < 12.0 ? 0.2 - 0.05 * (x - 10.0) * (x - 10.0) : 0.0);
  }
  spec.initial_depth.assign(static_cast<std::size_t>(cells), 2.0);
  return spec;
}

void close_bump_channel(Canal& canal, int upstream_reach, int downstream_reach) {
  ASSERT_TRUE(canal.set_boundary(upstream_reach, End::upstream, FixedDischargeBoundary::constant(4.42)));
  ASSERT_TRUE(canal.set_boundary(downstream_reach, End::downstream, FixedLevelBoundary::depth(2.0)));
}

double max_depth_difference(const Canal& a, const Canal& b) {
  double worst = 0.0;
  for (int r = 0; r < a.reach_count(); ++r) {
    for (int i = 0; i < a.reach(r).cells(); ++i) {
      worst = std::max(worst, std::abs(a.reach(r).depth(i) - b.reach(r).depth(i)));
    }
  }
  return worst;
}

TEST(SteadyState, NewtonGivesTheStateLongTimeMarchingConvergesTo) {
  Canal newton, marching;
  ASSERT_TRUE(newton.add_reach(bump_channel(50)));
  ASSERT_TRUE(marching.add_reach(bump_channel(50)));
  close_bump_channel(newton, 0, 0);
  close_bump_channel(marching, 0, 0);
  const auto summary = solve_steady_state(newton);
  ASSERT_TRUE(summary.status) << summary.status.message();
  EXPECT_LT(summary.max_depth_rate, 1e-9);
  ASSERT_TRUE(marching.advance_to(1500.0));
  EXPECT_LT(max_depth_difference(newton, marching), 1e-8);
}

TEST(SteadyState, AStepFromItCarriesTheInflowOutAndStoresNothing) {
  // Mass conservation at steady state: the face fluxes are equal, so a step passes the inflow to
  // the outlet and the stored volume does not change.
  Canal canal;
  ASSERT_TRUE(canal.add_reach(bump_channel(80)));
  close_bump_channel(canal, 0, 0);
  ASSERT_TRUE(solve_steady_state(canal).status);
  canal.reset_balance();
  ASSERT_TRUE(canal.step());
  const VolumeBalance b = canal.total_balance();
  EXPECT_NEAR(b.outflow, b.inflow, 1e-9 * b.inflow);
  EXPECT_LT(std::abs(b.storage_change()), 1e-9 * b.inflow);
}

TEST(SteadyState, TwoReachesJoinedByALinkMatchTimeMarching) {
  Canal newton, marching;
  for (Canal* c : {&newton, &marching}) {
    ASSERT_TRUE(c->add_reach(bump_channel(30)));
    ReachSpec second = bump_channel(20, 15.0);
    second.bed_elevation.assign(20, 0.0);
    ASSERT_TRUE(c->add_reach(second));
    ASSERT_TRUE(c->connect(0, 1, std::make_shared<ContinuousLink>()));
    close_bump_channel(*c, 0, 1);
  }
  const auto summary = solve_steady_state(newton);
  ASSERT_TRUE(summary.status) << summary.status.message();
  ASSERT_TRUE(marching.advance_to(1500.0));
  EXPECT_LT(max_depth_difference(newton, marching), 1e-8);
}

TEST(SteadyState, NoSteadyStateIsAReturnedFailureThatKeepsTheState) {
  // Inflow into a channel closed by a wall: the level rises for ever.
  Canal canal;
  ASSERT_TRUE(canal.add_reach(bump_channel(20)));
  ASSERT_TRUE(canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(1.0)));
  ASSERT_TRUE(canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>()));
  const std::vector<double> before = canal.reach(0).area();
  SteadyStateOptions options;
  options.continuation_attempts = 0;
  const auto summary = solve_steady_state(canal, options);
  EXPECT_FALSE(summary.status);
  EXPECT_NE(summary.status.message().find("steady state not found"), std::string::npos);
  EXPECT_EQ(canal.reach(0).area(), before);
}

// The bump channel with the generalised minmod limiter: on 400 cells its one-sided slopes tie
// along the nearly straight profile and Newton stalls at the kinks short of its tolerance (on 150
// to 300 cells it converges).
Canal minmod_bump_channel(double inflow = 4.42) {
  SolverOptions o;
  o.limiter = Limiter::generalised_minmod;
  o.cfl = 0.45;  // below minmod's limit cycle (docs/numerics.md)
  Canal canal(o);
  EXPECT_TRUE(canal.add_reach(bump_channel(400)));
  EXPECT_TRUE(canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(inflow)));
  EXPECT_TRUE(canal.set_boundary(0, End::downstream, FixedLevelBoundary::depth(2.0)));
  return canal;
}

TEST(SteadyState, AStallAtMinmodsKinksIsAcceptedOnlyWithinTheBoundsAskedFor) {
  SteadyStateOptions strict;
  strict.continuation_attempts = 0;
  Canal refused = minmod_bump_channel();
  const std::vector<double> before = refused.reach(0).area();
  const auto failure = solve_steady_state(refused, strict);
  ASSERT_FALSE(failure.status) << "Newton converged: this canal no longer shows the stall";
  EXPECT_EQ(refused.reach(0).area(), before);  // a stall not asked for is a failure that keeps the state

  SteadyStateOptions tolerant = strict;
  tolerant.stalled_depth_rate = 1e-6;  // measured stall: 1.0e-7 m/s, 2.8e-7 m³/s² (6.4e-8 of Q per s)
  tolerant.stalled_discharge_rate = 1e-6;
  Canal newton = minmod_bump_channel();
  const auto summary = solve_steady_state(newton, tolerant);
  ASSERT_TRUE(summary.status) << summary.status.message();
  EXPECT_TRUE(summary.stalled);
  EXPECT_NE(summary.stall.find("stalled after"), std::string::npos) << summary.stall;
  EXPECT_LE(summary.max_depth_rate, tolerant.stalled_depth_rate);
  // That it is where time marching goes: Simulate.AStalledSteadyStateStartsWhereTheMarchWould
  // (tests/scenarios/simulate_test.cpp), on the lab canal.

  // A bound the stall does not meet is a failure, as without one.
  SteadyStateOptions too_strict = strict;
  too_strict.stalled_depth_rate = 1e-30;
  too_strict.stalled_discharge_rate = 1e-30;
  Canal again = minmod_bump_channel();
  EXPECT_FALSE(solve_steady_state(again, too_strict).status);
  EXPECT_EQ(again.reach(0).area(), before);
}

// Continuation marches run the boundaries: one whose inflow changes at t = 100 s must be solved
// at least continuation_span before it for every attempt to see the inflow before the change.
TEST(SteadyState, ContinuationMarchesStayWithinTheirSpan) {
  const double change_at = 100.0, before_change = 2.0, after_change = 4.42;
  auto canal_with_changing_inflow = [&] {
    Canal canal;
    EXPECT_TRUE(canal.add_reach(bump_channel(50)));
    const auto inflow = [&](double t) { return t < change_at ? before_change : after_change; };
    EXPECT_TRUE(canal.set_boundary(0, End::upstream, std::make_shared<FixedDischargeBoundary>(inflow)));
    EXPECT_TRUE(canal.set_boundary(0, End::downstream, FixedLevelBoundary::depth(2.0)));
    return canal;
  };
  SteadyStateOptions options;
  options.first_guess = false;
  options.max_iterations = 1;  // every attempt but a late one fails: the marches must happen
  options.continuation_attempts = 20;
  const auto steady_discharge = [&](double start) {
    Canal canal = canal_with_changing_inflow();
    canal.set_time(start);
    const auto summary = solve_steady_state(canal, options);
    EXPECT_TRUE(summary.status) << summary.status.message();
    EXPECT_EQ(canal.time(), start);
    return canal.reach(0).discharge().front();
  };
  Canal probe = canal_with_changing_inflow();
  const double span = continuation_span(probe, options);
  ASSERT_GT(span, 0.0);
  EXPECT_NEAR(steady_discharge(change_at - span - 1e-9), before_change, 1e-3);
  // The same solve started just before the change settles on the inflow after it.
  EXPECT_NEAR(steady_discharge(change_at - 1e-9), after_change, 1e-3);
}

TEST(SteadyState, InvalidOptionsNameTheField) {
  SteadyStateOptions options;
  options.depth_tolerance = -1.0;
  EXPECT_NE(options.validate().message().find("depth_tolerance"), std::string::npos);
  options = {};
  options.max_iterations = 0;
  EXPECT_NE(options.validate().message().find("max_iterations"), std::string::npos);
  options = {};
  options.stalled_depth_rate = -1e-9;
  EXPECT_NE(options.validate().message().find("stalled_depth_rate"), std::string::npos);
}

// An offtake at the end face of a horizontal, frictionless channel (inflow Q_in upstream, level
// h_d held downstream, Q_w withdrawn just upstream of the end): mass and momentum balance with
// the level continuous across the offtake give the closed form h ≡ h_d and Q ≡ Q_in in every
// cell, and Q_in − Q_w through the end. The same withdrawal inside the last cell leaves that
// cell carrying about the mean of Q_in and Q_in − Q_w, which the HLL flux to its neighbour passes
// only through a depth dip of about Q_w / (2 c T) — the reason for the face withdrawal
// (docs/asce-canals.md).
Canal channel_with_offtake(bool at_end_face) {
  Canal canal;
  EXPECT_TRUE(canal.add_reach(testing::uniform_reach(100.0, 50, {1.0, 0.0}, 0.0, 1.0)));
  EXPECT_TRUE(canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(0.5)));
  EXPECT_TRUE(canal.set_boundary(0, End::downstream, FixedLevelBoundary::depth(1.0)));
  if (at_end_face) {
    canal.reach(0).fixed_end_withdrawal() = 0.2;
  } else {
    canal.reach(0).lateral_inflow().back() = -0.2 / canal.reach(0).cell_length();
  }
  return canal;
}

TEST(EndWithdrawal, SteadyFlowKeepsTheLevelAndCarriesTheInflowToTheOfftake) {
  Canal canal = channel_with_offtake(true);
  const auto summary = solve_steady_state(canal);
  ASSERT_TRUE(summary.status) << summary.status.message();
  const Reach& r = canal.reach(0);
  for (int i = 0; i < r.cells(); ++i) {
    EXPECT_NEAR(r.depth(i), 1.0, 1e-10) << "cell " << i;
    EXPECT_NEAR(r.discharge()[static_cast<std::size_t>(i)], 0.5, 1e-10) << "cell " << i;
  }
  // A step from it: the end passes Q_in − Q_w, the offtake is booked as lateral outflow.
  canal.reset_balance();
  ASSERT_TRUE(canal.step());
  const double dt = canal.statistics().last_dt;
  const VolumeBalance b = canal.total_balance();
  EXPECT_NEAR(b.outflow / dt, 0.3, 1e-10);
  EXPECT_NEAR(b.lateral / dt, -0.2, 1e-12);
  EXPECT_NEAR(r.last_end_withdrawal(), 0.2, 0.0);

  Canal in_cell = channel_with_offtake(false);
  ASSERT_TRUE(in_cell.advance_to(600.0));  // ~20 wave crossings (Newton needs a better start here)
  const double c = std::sqrt(9.81);
  EXPECT_LT(in_cell.reach(0).depth(49), 1.0 - 0.5 * 0.2 / (2.0 * c));  // the dip, at least half of it
}

}  // namespace
}  // namespace canalsim::solver
