// Physics outside the diagnosis catalog (scenarios/outside_catalog.hpp) against closed forms:
//   - the play operator on hand-computed sequences, and its defining properties on a long one;
//   - a lab experiment behind a gate backlash: the gate switches at the PRBS clock edges to the
//     play's output, ±(A − b/2) about the operating point, and the recording's u_mm is the PRBS;
//     with a rate-limited actuator the gate follows the play of the motor's eq. (16) path, which
//     the test integrates on its own;
//   - a depth seepage: at the reference state its outlets take the asked share of the inflow; in
//     steady states at two operating levels the volume balance's lateral outflow equals the law
//     Σ K (h − h0)^(3/2) at the canal's depths, and its share of the inflow changes severalfold.
#include "scenarios/outside_catalog.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/laws.hpp"
#include "core/metadata.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/design.hpp"
#include "scenarios/prbs.hpp"

namespace canalsim::scenarios {
namespace {

constexpr double kMm = 1e-3;

void expect_sequence(const std::vector<double>& actual, const std::vector<double>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) EXPECT_DOUBLE_EQ(actual[k], expected[k]) << "sample " << k;
}

TEST(PlayOperator, HandComputedSequenceWithReversalsAndTravelThroughThePlay) {
  // Width 2 (half-width 1), starting at 0. Rising to 1 only takes up the play; at 3 the gate is
  // pushed to 2; back down to 1.9 it stays (the command crosses the play); at 0 it is pulled to 1;
  // up again to 1.5 the play is crossed once more; at 2.5 it is pushed to 1.5.
  const std::vector<double> u{0.0, 0.5, 1.0, 3.0, 2.5, 2.0, 1.9, 0.0, 0.5, 1.5, 2.5};
  expect_sequence(play_operator(u, 2.0, 0.0), {0.0, 0.0, 0.0, 2.0, 2.0, 2.0, 2.0, 1.0, 1.0, 1.0, 1.5});
}

TEST(PlayOperator, WidthZeroIsTheIdentityAndAnInitialOutputOutsideThePlayIsPulledIn) {
  const std::vector<double> u{3.0, -1.0, 7.5, 7.5, 0.25};
  expect_sequence(play_operator(u, 0.0, 100.0), u);
  // Initial 10 with the first command 3 and half-width 0.5: the output starts at 3.5.
  expect_sequence(play_operator({3.0, 3.2, 4.5}, 1.0, 10.0), {3.5, 3.5, 4.0});
  EXPECT_TRUE(play_operator({}, 1.0, 0.0).empty());
  EXPECT_THROW(play_operator(u, -0.1, 0.0), std::invalid_argument);
  EXPECT_THROW(play_operator(u, std::nan(""), 0.0), std::invalid_argument);
  EXPECT_THROW(play_operator(u, 1.0, INFINITY), std::invalid_argument);
}

// The play's definition, checked on a random walk: the command never leaves the play
// (|u − w| <= b/2), and the output moves only when the command pushes it from an end of the play
// (|u − w| = b/2 exactly after every move).
TEST(PlayOperator, OnARandomWalkTheOutputMovesOnlyWhenPushedByAnEndOfThePlay) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> step(0.0, 0.7);
  std::vector<double> u{0.0};
  for (int k = 0; k < 5000; ++k) u.push_back(u.back() + step(rng));
  const double width = 1.3;
  const std::vector<double> w = play_operator(u, width, 0.0);
  int moves = 0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    EXPECT_LE(std::abs(u[k] - w[k]), 0.5 * width + 1e-12);
    if (k > 0 && w[k] != w[k - 1]) {
      ++moves;
      EXPECT_NEAR(std::abs(u[k] - w[k]), 0.5 * width, 1e-12);
    }
  }
  EXPECT_GT(moves, 1000);
  EXPECT_LT(moves, 4900);  // the play holds the output on many of the reversals
}

ExperimentSpec lab_prbs(double opening_mm, double duration_s) {
  ExperimentSpec e;
  e.name = "backlash";
  e.operating_opening_mm = opening_mm;
  e.duration_s = duration_s;
  e.input.kind = InputKind::prbs;  // the lab's 9 stages, 0.5 s clock, ±5 mm, seed 1
  return e;
}

// The experiment's own PRBS as the signal the simulator builds (scenarios/prbs.hpp).
PrbsSignal prbs_of(const ExperimentSpec& e) {
  PrbsOptions o;
  o.stages = e.input.prbs_stages;
  o.clock_period = e.input.prbs_clock_s;
  o.amplitude = e.input.amplitude_mm * kMm;
  o.operating_point = e.operating_opening_mm * kMm;
  o.seed = e.input.prbs_seed;
  return PrbsSignal(o);
}

// An ideal actuator, b = 2 mm, PRBS 25 ± 5 mm: every clock edge reverses the command by 10 mm,
// through the 2 mm play, so the gate switches at every edge and lands b/2 short of the command:
// at 25 ± 4 mm, on the command's side.
TEST(GateBacklash, TheIdealGateSwitchesAtThePrbsClockEdgesToThePlaysOutput) {
  const Scenario lab = builtin_scenario("lab");
  const ExperimentSpec e = lab_prbs(25.0, 60.0);
  const Recording drive = backlash_drive(lab, e, 2.0);
  const PrbsSignal prbs = prbs_of(e);
  std::vector<double> edges = prbs.jumps(-1e-9, e.duration_s);
  ASSERT_GT(edges.size(), 40u);
  ASSERT_EQ(edges.front(), 0.0);  // the first bit leaves the operating point at t = 0
  const auto& t = drive.column("t_s");
  const auto& u = drive.column("u_mm");
  ASSERT_EQ(t.size(), edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    EXPECT_EQ(t[k], edges[k]) << "move " << k;  // exactly the clock edge, not a sample time
    const double side = prbs.value(edges[k]) > e.operating_opening_mm * kMm ? 1.0 : -1.0;
    EXPECT_NEAR(u[k], 25.0 + side * 4.0, 1e-12) << "move " << k;
  }
  EXPECT_EQ(metadata_number(drive, "operating_opening_mm"), 25.0);
  // The simulator ends its steps at the drive's jumps, which are the PRBS's own.
  const BuiltCanal built = build_canal(lab, e, Drive{&drive});
  const std::vector<double> breaks = built.command->jumps(0.0, e.duration_s);
  const std::vector<double> prbs_breaks = prbs.jumps(0.0, e.duration_s);
  ASSERT_EQ(breaks.size(), prbs_breaks.size());
  for (std::size_t k = 0; k < breaks.size(); ++k) EXPECT_EQ(breaks[k], prbs_breaks[k]);
}

// The recording of a simulated backlash: u_mm is the experiment's PRBS (what the logger
// records), x_up_mm the play operator of it from the operating opening — the sampling at 0.13 s
// holds every 0.5 s level of the command, so the play of the samples is the play of the signal.
// The gate therefore sits 1 mm (b/2) on the near side of every command, and the flow through it
// swings less than without the play.
//
// A sample in the solver step that ends at a clock edge is the linear interpolation between the
// states before and after that step (simulate.cpp), so its x_up is a mix of the opening before
// the edge and the one after; the run without backlash shows the same at such samples. There x_up
// must lie between the two play outputs.
TEST(GateBacklash, ASimulatedGateFollowsThePlayOfTheRecordedCommand) {
  const Scenario lab = builtin_scenario("lab");
  const ExperimentSpec e = lab_prbs(25.0, 60.0);
  const Recording rec = simulate_with_backlash(lab, e, 2.0);
  const Recording plain = simulate(lab, e);
  const PrbsSignal prbs = prbs_of(e);
  const auto& t = rec.column("t_s");
  const auto& u = rec.column("u_mm");
  const auto& x = rec.column("x_up_mm");
  ASSERT_EQ(u.size(), plain.size());
  for (std::size_t k = 0; k < u.size(); ++k) {
    EXPECT_EQ(u[k], prbs.value(t[k]) / kMm) << "t = " << t[k];
    EXPECT_EQ(u[k], plain.column("u_mm")[k]) << "t = " << t[k];
  }
  const std::vector<double> expected = play_operator(u, 2.0, 25.0);
  std::size_t exact = 0, mixed = 0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (std::abs(x[k] - expected[k]) <= 1e-6) {
      ++exact;
      EXPECT_NEAR(std::abs(u[k] - x[k]), 1.0, 1e-6) << "t = " << t[k];
      continue;
    }
    ++mixed;
    const double edge = std::ceil(t[k] / 0.5 + 1e-9) * 0.5;  // the next clock edge
    const double next = play_operator({prbs.value(edge) / kMm}, 2.0, expected[k]).front();
    EXPECT_LT(edge - t[k], 0.2) << "t = " << t[k] << ": off the play away from a clock edge";
    EXPECT_GE(x[k], std::min(expected[k], next) - 1e-9) << "t = " << t[k];
    EXPECT_LE(x[k], std::max(expected[k], next) + 1e-9) << "t = " << t[k];
  }
  EXPECT_LT(mixed, u.size() / 20);
  EXPECT_EQ(exact + mixed, u.size());
  const auto swing = [](const std::vector<double>& q) {
    const auto [lo, hi] = std::minmax_element(q.begin() + static_cast<std::ptrdiff_t>(q.size() / 4), q.end());
    return *hi - *lo;
  };
  EXPECT_LT(swing(rec.column("q_lps")), 0.95 * swing(plain.column("q_lps")));
  EXPECT_EQ(rec.meta("operating_opening_mm"), plain.meta("operating_opening_mm"));
}

// The gate position of a rate-limited drive, integrated independently: the motor follows the
// PRBS by eq. (16) in steps of 0.1 ms, the gate follows the motor through the play.
std::vector<double> dense_gate_path(const PrbsSignal& prbs, double speed, double width, double rest,
                                    const std::vector<double>& at) {
  const double dt = 1e-4;
  double motor = rest, gate = rest, time = 0.0;
  std::vector<double> out;
  for (double t : at) {
    while (time < t - 0.5 * dt) {
      motor = laws::rate_limited_move(motor, prbs.value(time + 1e-12), speed * dt);
      gate = play_operator({motor}, width, gate).front();
      time += dt;
    }
    out.push_back(gate);
  }
  return out;
}

// A rate-limited actuator (5 mm/s) with a 2 mm play: after a reversal the motor must cross the
// play, 0.4 s, before the gate moves. The simulated x_up follows the independent path to within
// the sampling's interpolation: a sample in the solver step where the gate stops is interpolated
// linearly across the stop, off by up to v · dt / 4 (0.05 mm for the lab's ~0.04 s steps; 0.1 mm
// allows 0.08 s). Putting the rate limit after the play instead (the gate starting at once)
// misses the path by up to v · 0.4 s = 2 mm.
TEST(GateBacklash, ARateLimitedGateWaitsForTheMotorToCrossThePlay) {
  Scenario lab = builtin_scenario("lab");
  const double speed = 0.005;
  lab.head_gate->actuator_speed_m_s = speed;
  const ExperimentSpec e = lab_prbs(25.0, 60.0);
  const Recording rec = simulate_with_backlash(lab, e, 2.0);
  const PrbsSignal prbs = prbs_of(e);
  const auto& t = rec.column("t_s");
  const std::vector<double> path = dense_gate_path(prbs, speed, 2.0 * kMm, 25.0 * kMm, t);
  // Play after the rate limit's wrong order: the gate heads for the play's output at once.
  std::vector<double> wrong_order;
  {
    const double dt = 1e-4;
    double time = 0.0, gate = 25.0 * kMm, target = gate;
    for (double tk : t) {
      while (time < tk - 0.5 * dt) {
        target = play_operator({prbs.value(time + 1e-12)}, 2.0 * kMm, target).front();
        gate = laws::rate_limited_move(gate, target, speed * dt);
        time += dt;
      }
      wrong_order.push_back(gate);
    }
  }
  double largest = 0.0, largest_wrong = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    largest = std::max(largest, std::abs(rec.column("x_up_mm")[k] - path[k] / kMm));
    largest_wrong = std::max(largest_wrong, std::abs(wrong_order[k] - path[k]) / kMm);
  }
  EXPECT_LT(largest, 0.1);
  EXPECT_GT(largest_wrong, 1.5);
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_EQ(rec.column("u_mm")[k], prbs.value(t[k]) / kMm);
}

TEST(GateBacklash, ARampOrAnUncontrolledCanalIsRefused) {
  Scenario lab = builtin_scenario("lab");
  ExperimentSpec e = lab_prbs(25.0, 20.0);
  e.input.kind = InputKind::ramp;
  EXPECT_THROW(backlash_drive(lab, e, 1.0), InputError);
  e.input.kind = InputKind::prbs;
  EXPECT_THROW(backlash_drive(lab, e, -1.0), InputError);
  lab.head_gate->controlled = false;
  EXPECT_THROW(backlash_drive(lab, e, 1.0), InputError);
}



// --- depth seepage ------------------------------------------------------------------------------

struct SteadyRun {
  Recording rec;
  std::vector<double> depth;  // at each seepage outlet's cell [m]
  double inflow = 0.0;        // into the first pool at the end [m³/s]
};

// The lab held at one opening for `duration` s from its steady state; depths read at the cells of
// `seepage`'s outlets.
SteadyRun steady_run(const Scenario& s, const PoolSpec& seepage, double opening_mm, double duration) {
  ExperimentSpec e;
  e.name = "held";
  e.operating_opening_mm = opening_mm;
  e.duration_s = duration;
  e.input.kind = InputKind::constant;
  SteadyRun run;
  SimulateOptions options;
  options.on_finish = [&](const BuiltCanal& b) {
    for (const OfftakeSpec& o : seepage.offtakes) run.depth.push_back(b.canal.reach(0).depth(offtake_cell(seepage, o.x_m)));
    run.inflow = b.canal.reach(0).discharge().front();
  };
  run.rec = simulate(s, e, options);
  return run;
}

// The seepage law's closed form at the given depths [m³/s].
double seepage_law(const PoolSpec& pool, const std::vector<double>& depth) {
  double q = 0.0;
  for (std::size_t k = 0; k < pool.offtakes.size(); ++k) {
    const OfftakeSpec& o = pool.offtakes[k];
    q += o.coefficient * std::pow(std::max(depth[k] - o.invert_m, 0.0), o.exponent);
  }
  return q;
}

double meta(const Recording& rec, const char* key) {
  const auto value = metadata_number(rec, key);
  EXPECT_TRUE(value.has_value()) << key;
  return value.value_or(NAN);
}

// Sized at op1's level (the lab's first experiment, 15 mm): five outlets along the main pool,
// 5 mm of head each at the seepage-free steady state, together 10 % of that state's inflow.
TEST(DepthSeepage, AtTheReferenceStateTheOutletsTakeTheAskedShare) {
  const Scenario lab = builtin_scenario("lab");
  Scenario leaky = lab;
  add_depth_seepage(leaky, 0.10);
  const PoolSpec& pool = leaky.pools.front();
  ASSERT_EQ(pool.offtakes.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {
    const OfftakeSpec& o = pool.offtakes[k];
    EXPECT_NEAR(o.x_m, (k + 0.5) * 4.5 / 5, 1e-12);
    EXPECT_EQ(o.kind, OfftakeKind::orifice);
    EXPECT_EQ(o.exponent, 1.5);
  }
  const SteadyRun reference = steady_run(lab, pool, 15.0, 0.13);  // the lab without the seepage
  for (std::size_t k = 0; k < 5; ++k) EXPECT_NEAR(reference.depth[k] - pool.offtakes[k].invert_m, 5.0 * kMm, 1e-12);
  EXPECT_NEAR(seepage_law(pool, reference.depth), 0.10 * reference.inflow, 1e-12 * reference.inflow);
  EXPECT_NEAR(reference.inflow, 0.476e-3, 0.002e-3);  // op1's steady flow, 0.476 L/s
}

// The seeping lab in steady states at op1's and op4's openings. Per state the balance's lateral
// volume over 20 s is the law's outflow at the canal's depths, inflow − outflow + lateral closes,
// and the gate passes the outflow plus the seepage. At op4 the level stands ~12 mm higher: the
// seepage takes a far larger share of a larger inflow, where a fixed share of the inflow (the
// catalog's lateral_outflow) would take the same share.
TEST(DepthSeepage, TheSteadyOutflowFollowsTheLawAtTwoOperatingLevels) {
  Scenario leaky = builtin_scenario("lab");
  add_depth_seepage(leaky, 0.10);
  const PoolSpec& pool = leaky.pools.front();
  const double duration = 20.0;
  std::vector<double> share;
  for (double opening : {15.0, 45.0}) {
    const SteadyRun run = steady_run(leaky, pool, opening, duration);
    const double law = seepage_law(pool, run.depth);
    // The balance runs to the last step's end, just short of the duration.
    const double until = meta(run.rec, "volume_until_s");
    EXPECT_NEAR(until, duration, 0.2);
    const double lateral = meta(run.rec, "volume_lateral_m3");
    const double inflow = meta(run.rec, "volume_inflow_m3");
    const double outflow = meta(run.rec, "volume_outflow_m3");
    const double storage = meta(run.rec, "volume_storage_change_m3");
    EXPECT_NEAR(-lateral / until, law, 1e-3 * law) << "opening " << opening;
    EXPECT_NEAR(inflow - outflow + lateral, storage, 1e-9 * inflow) << "opening " << opening;
    EXPECT_NEAR(storage, 0.0, 1e-3 * inflow) << "steady";
    EXPECT_NEAR(inflow / until, run.inflow, 1e-3 * run.inflow) << "opening " << opening;
    EXPECT_NEAR(inflow / until, outflow / until + law, 1e-3 * run.inflow) << "opening " << opening;
    share.push_back(law / run.inflow);
    std::printf("opening %g mm: inflow %.4f L/s, seepage %.4f L/s (%.1f %%), depths %.2f .. %.2f mm, "
                "lateral/law %.5f\n",
                opening, run.inflow / kMm, law / kMm, 100 * share.back(), run.depth.front() / kMm,
                run.depth.back() / kMm, -lateral / until / law);
  }
  // At op1, its own reference, the levels dropped with the seepage: less than the 10 % asked.
  EXPECT_LT(share[0], 0.10);
  EXPECT_GT(share[0], 0.03);
  EXPECT_GT(share[1], 3.0 * share[0]);
}



TEST(DepthSeepage, BadOptionsAreRefusedAndAZeroShareAddsNothing) {
  Scenario lab = builtin_scenario("lab");
  add_depth_seepage(lab, 0.0);
  EXPECT_TRUE(lab.pools.front().offtakes.empty());
  EXPECT_THROW(add_depth_seepage(lab, 1.0), std::invalid_argument);
  EXPECT_THROW(add_depth_seepage(lab, -0.1), std::invalid_argument);
  DepthSeepageOptions o;
  o.pool = 1;
  EXPECT_THROW(add_depth_seepage(lab, 0.1, o), std::invalid_argument);
  o = {};
  o.exponent = 3.5;
  EXPECT_THROW(add_depth_seepage(lab, 0.1, o), std::invalid_argument);
  o = {};
  o.head_mm = 80.0;  // deeper than the pool at op1
  EXPECT_THROW(add_depth_seepage(lab, 0.1, o), std::invalid_argument);
  o = {};
  o.reference_experiment = "no such";
  EXPECT_THROW(add_depth_seepage(lab, 0.1, o), InputError);
  EXPECT_TRUE(lab.pools.front().offtakes.empty());
}

}  // namespace
}  // namespace canalsim::scenarios
