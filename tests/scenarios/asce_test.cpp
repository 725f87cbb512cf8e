// The ASCE test canals (scenarios/builtin/asce1_canal.toml, asce2_canal.toml): with the automatic
// gate openings, the Newton steady state sits at the target depths and passes the design flows of
// ../shared/reference/asce_canals.json (copied below); the flow-change run closes its water
// balance against the inflow and pumping integrated by hand; after the change the canal settles
// to the steady state Newton finds directly for the new flows; bad input gives one line.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <gtest/gtest.h>
#include <string>
#include <vector>

#include "scenarios/builtin.hpp"
#include "scenarios/design.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/simulate.hpp"
#include "solver/steady_state.hpp"

namespace canalsim::scenarios {
namespace {

struct Reference {
  const char* name;
  std::vector<double> target_depth_m;  // asce_canals.json
  std::vector<double> check_flows_m3s; // flow leaving each pool through its downstream end
  double depth_tolerance_m;
};

// Check depth of pool i: the level extrapolated to the pool's downstream end, above the bed there.
double check_depth(const BuiltCanal& b, int i) { return b.check_depth(i); }

BuiltCanal steady_canal(const Scenario& s) {
  BuiltCanal b = build_canal(s, *s.find_experiment("steady"));
  const auto summary = solver::solve_steady_state(b.canal);
  EXPECT_TRUE(summary.status) << summary.status.message();
  return b;
}

// The flow through each check (the gate's mass flux) and out of the end over one step from the
// steady state: the face fluxes, not the cell discharges (which differ by the scheme's numerical
// diffusion where the jet meets the pool).
std::vector<double> check_flows(BuiltCanal& b) {
  b.canal.reset_balance();
  EXPECT_TRUE(b.canal.step());
  std::vector<double> q;
  for (const auto& link : b.gate_links) q.push_back(link->last_discharge());
  q.push_back(b.canal.total_balance().outflow / b.canal.statistics().last_dt);
  return q;
}

// The design computation (RK4 on the gradually varied flow equation, the Swamee law inverted at
// the target depths) and the finite-volume steady state are independent discretisations of the
// same steady flow; they differ by the scheme's truncation error (50-100 m cells) and, in canal 1,
// by the hydraulic jumps below its free-flowing checks, which the design's backwater curves do
// not contain. Measured: docs/asce-canals.md.
class AsceSteadyState : public testing::TestWithParam<Reference> {};

// Canal 2's checks are drowned, so every pool is one subcritical backwater curve from end to end:
// each cell of the steady state lies on the design profile at its centre.
TEST(AsceSteadyState, Canal2CellsLieOnTheDesignBackwaterProfiles) {
  const Scenario s = resolve_design(builtin_scenario("asce2"));
  BuiltCanal b = steady_canal(s);
  double worst = 0.0;
  for (int i = 0; i < 8; ++i) {
    const auto& r = b.canal.reach(i);
    for (int k = 0; k < r.cells(); ++k) {
      const double design = s.pools[static_cast<std::size_t>(i)].design_depth_m[static_cast<std::size_t>(k)];
      EXPECT_NEAR(r.depth(k), design, 2e-4) << "pool " << i + 1 << " cell " << k;
      worst = std::max(worst, std::abs(r.depth(k) - design));
    }
  }
  std::printf("asce2: worst cell depth off the design profile %.3f mm\n", worst * 1e3);
}

TEST_P(AsceSteadyState, AutoOpeningsHoldTheTargetDepthsAndPassTheDesignFlows) {
  const Reference& ref = GetParam();
  BuiltCanal b = steady_canal(builtin_scenario(ref.name));
  double worst_depth = 0.0, worst_flow = 0.0;
  const std::vector<double> flows = check_flows(b);
  for (int i = 0; i < 8; ++i) {
    const double error = check_depth(b, i) - ref.target_depth_m[static_cast<std::size_t>(i)];
    EXPECT_LE(std::abs(error), ref.depth_tolerance_m) << ref.name << " pool " << i + 1;
    worst_depth = std::max(worst_depth, std::abs(error));
    // The flow leaving pool i: through its check, or out of the end (pump, or 0 at a wall).
    const double q = flows[static_cast<std::size_t>(i)];
    const double design = ref.check_flows_m3s[static_cast<std::size_t>(i)];
    const double relative = design > 0.0 ? std::abs(q / design - 1.0) : std::abs(q);
    EXPECT_LE(relative, 0.01) << ref.name << " check " << i + 1 << ": " << q << " m3/s";
    worst_flow = std::max(worst_flow, relative);
  }
  std::printf("%s: worst check-depth error %.1f mm, worst check-flow error %.3f %%\n", ref.name,
              worst_depth * 1e3, worst_flow * 100.0);
}

INSTANTIATE_TEST_SUITE_P(
    Canals, AsceSteadyState,
    testing::Values(Reference{"asce1",
                              {0.9, 0.9, 0.8, 0.9, 0.9, 0.8, 0.8, 0.8},
                              {0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1, 0.0},
                              0.005},
                    Reference{"asce2",
                              {2.1, 2.1, 2.1, 1.9, 1.9, 1.7, 1.7, 1.7},
                              {12.0, 10.2, 7.5, 7.2, 7.0, 6.2, 5.0, 2.7},
                              0.001}),
    [](const testing::TestParamInfo<Reference>& info) { return std::string(info.param.name); });

// asce2's test1 with its events moved to t = early and a short duration (the full 12 h run is
// documented in docs/asce-canals.md).
ExperimentSpec shortened_test1(const Scenario& s, double event_t, double duration) {
  ExperimentSpec e = *s.find_experiment("test1");
  for (auto& ev : e.events) ev.t_s = event_t;
  e.duration_s = duration;
  return e;
}

TEST(AsceFlowChange, WaterBalanceCloses) {
  const Scenario s = builtin_scenario("asce2");
  const ExperimentSpec e = shortened_test1(s, 600.0, 1800.0);
  solver::VolumeBalance balance;
  double end = 0.0;  // the last step ends at or after the last sample
  SimulateOptions options;
  options.on_finish = [&](const BuiltCanal& b) {
    balance = b.canal.total_balance();
    end = b.canal.time();
  };
  simulate(s, e, options);
  // Independent: the head inflow and the pump integrated by hand over the run.
  EXPECT_NEAR(balance.inflow, 13.7 * 600.0 + 14.3 * (end - 600.0), 1e-9 * 13.7 * end);
  EXPECT_NEAR(balance.outflow, 2.7 * end, 1e-9 * 2.7 * end);
  // Storage change = inflow − outflow + lateral (offtakes, negative).
  EXPECT_LT(balance.relative_error(), 1e-12) << balance.error() << " m3";
  EXPECT_LT(balance.lateral, 0.0);
}

// The drowned checks couple pools 5-8 into one reservoir of ~9 ha whose outflow (the orifices)
// changes by ~1.3 m³/s per m of level: a time constant of ~15 h, so settling to 1 mm takes
// two to three days of canal time. Coarse cells (one quarter as many) and the first-order scheme at
// Courant number 0.9 keep that run to a few seconds; the Newton reference solves the same
// discrete equations, so the comparison stays exact.
Scenario coarse_asce2() {
  Scenario s = builtin_scenario("asce2");
  for (auto& p : s.pools) p.cells = std::max(4, p.cells / 4);
  s.numerics.order = 1;
  s.numerics.cfl = 0.9;
  return s;
}

TEST(AsceFlowChange, CanalSettlesToTheNewtonSteadyStateOfTheNewFlows) {
  const Scenario s = coarse_asce2();
  const ExperimentSpec e = shortened_test1(s, 60.0, 54.0 * 3600.0);
  std::vector<double> marched;
  SimulateOptions options;
  options.on_finish = [&](const BuiltCanal& b) {
    for (int i = 0; i < 8; ++i) marched.push_back(check_depth(b, i));
  };
  simulate(s, e, options);

  // The new flows applied directly to the resolved scenario (openings and orifices as designed,
  // each orifice's coefficient scaled by new/design discharge, the new head inflow).
  Scenario changed = resolve_design(s);
  for (const auto& ev : e.events) {
    if (ev.inflow_m3s >= 0.0) changed.upstream.discharge_m3s = ev.inflow_m3s;
    if (ev.pool > 0) {
      auto& o = changed.pools[static_cast<std::size_t>(ev.pool - 1)].offtakes[static_cast<std::size_t>(ev.offtake - 1)];
      o.coefficient *= ev.offtake_m3s / o.discharge_m3s;
    }
  }
  BuiltCanal newton = steady_canal(changed);
  double worst = 0.0;
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(marched[static_cast<std::size_t>(i)], check_depth(newton, i), 1e-3) << "pool " << i + 1;
    worst = std::max(worst, std::abs(marched[static_cast<std::size_t>(i)] - check_depth(newton, i)));
  }
  std::printf("asce2 (coarse, first order) 54 h after the flow change: worst check-depth difference to Newton %.2f mm\n",
              worst * 1e3);
}

const char* kTwoPools = R"(
name = "two"
[upstream]
kind = "discharge"
discharge_m3s = 1.0
[[pools]]
length_m = 1000
bottom_width_m = 1.0
side_slope = 1.5
wall_height_m = 1.2
bed_slope = 0.001
bed_elevation_m = 2.0
target_depth_m = 0.9
[[pools.offtakes]]
x_m = 1000
kind = "orifice"
discharge_m3s = 0.5
[[gates]]
width_m = 1.5
max_opening_m = 1.0
opening_m = "auto"
[[pools]]
length_m = 1000
bottom_width_m = 1.0
side_slope = 1.5
wall_height_m = 1.2
bed_slope = 0.001
bed_elevation_m = 1.0
target_depth_m = 0.9
[[pools.offtakes]]
x_m = 1000
kind = "orifice"
discharge_m3s = 0.5
[downstream]
kind = "closed"
[[experiments]]
name = "steady"
[experiments.input]
kind = "constant"
)";

std::string error_of(const std::string& text) {
  try {
    const Scenario s = parse_scenario(text, "two.toml");
    build_canal(s, s.experiments.front());
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(AsceInput, TheTwoPoolTemplateIsValid) { EXPECT_EQ(error_of(kTwoPools), "no error"); }

TEST(AsceInput, AutoOpeningWithoutTargetDepthsIsOneLine) {
  const std::string text = replaced(kTwoPools, "target_depth_m = 0.9\n[[pools.offtakes]]\nx_m = 1000\nkind = \"orifice\"\ndischarge_m3s = 0.5\n[downstream]",
                                    "[downstream]");
  EXPECT_EQ(error_of(text), "two.toml:21: gates[0].opening_m = \"auto\": expected target_depth_m on the pools on both "
                            "sides (pools[0] and pools[1])");
}

TEST(AsceInput, OpeningThatIsNeitherANumberNorAutoIsOneLine) {
  EXPECT_EQ(error_of(replaced(kTwoPools, "opening_m = \"auto\"", "opening_m = \"half\"")),
            "two.toml:21: gates[0].opening_m = \"half\": expected a number in [0, max_opening_m] m or \"auto\"");
}

TEST(AsceInput, NegativePumpDischargeIsOneLine) {
  EXPECT_EQ(error_of(replaced(kTwoPools, "kind = \"closed\"", "kind = \"pump\"\npump_discharge_m3s = -1")),
            "two.toml:36: downstream.pump_discharge_m3s = -1: expected a number in [0, 100000] m^3/s");
}

TEST(AsceInput, OrificeWithoutTargetDepthIsOneLine) {
  EXPECT_EQ(error_of(replaced(kTwoPools, "target_depth_m = 0.9\n[[pools.offtakes]]\nx_m = 1000\nkind = \"orifice\"\ndischarge_m3s = 0.5\n[downstream]",
                              "[[pools.offtakes]]\nx_m = 1000\nkind = \"orifice\"\ndischarge_m3s = 0.5\n[downstream]")),
            "two.toml:31: pools[1].offtakes[0].kind = \"orifice\": expected the pool to have a target_depth_m above the "
            "invert_m to size the orifice");
}

TEST(AsceInput, HeadFlowThatDoesNotMatchTheOfftakesIsNamed) {
  EXPECT_EQ(error_of(replaced(kTwoPools, "discharge_m3s = 1.0", "discharge_m3s = 1.2")),
            "two.toml: upstream.discharge_m3s = 1.2: expected the offtakes' design discharges plus the end's outflow "
            "(1 m^3/s) for a steady design state");
}

TEST(AsceInput, EventOnAPoolThatDoesNotExistIsOneLine) {
  const std::string text = std::string(kTwoPools) + "[[experiments.events]]\nt_s = 60\npool = 3\nofftake_m3s = 0.4\n";
  EXPECT_EQ(error_of(text), "two.toml:42: experiments[0].events[0].pool = 3: expected an integer in [1, 2]");
}

TEST(AsceInput, AnInputSignalWithoutAControlledGateIsNamed) {
  EXPECT_EQ(error_of(replaced(kTwoPools, "kind = \"constant\"", "kind = \"prbs\"")),
            "two.toml:39: experiments[0].input.kind: an experiment with an input signal needs a gate with "
            "controlled = true; expected kind = \"constant\" without one");
}

}  // namespace
}  // namespace canalsim::scenarios
