// Design state (scenarios/design.hpp): the backwater profile against the Manning normal depth
// computed here independently by bisection, the inverted gate law against Swamee's published
// free-flow formula written out here, and the design flows against the offtakes' sums.
#include "scenarios/design.hpp"

#include <cmath>
#include <gtest/gtest.h>

#include "core/recording.hpp"

namespace canalsim::scenarios {
namespace {

PoolSpec long_trapezoid(double length_m, int cells, double bed_slope = 0.002) {
  PoolSpec p;
  p.name = "long";
  p.length_m = length_m;
  p.cells = cells;
  p.bottom_width_m = 1.0;
  p.side_slope = 1.5;
  p.manning_n = 0.014;
  p.bed_slope = bed_slope;
  p.wall_height_m = 2.0;
  return p;
}

// Manning: Q = A R^{2/3} sqrt(S0) / n, solved for the depth by bisection.
double normal_depth(double q, double b, double m, double n, double s0) {
  auto manning = [&](double y) {
    const double a = y * (b + m * y), p = b + 2.0 * y * std::sqrt(1.0 + m * m);
    return a * std::pow(a / p, 2.0 / 3.0) * std::sqrt(s0) / n;
  };
  double lo = 1e-6, hi = 10.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (manning(mid) < q ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(Backwater, LongChannelReachesTheManningNormalDepthFromAbove) {
  // M1 curve: 0.9 m at the end, normal depth ~0.37 m far upstream (decay length ~ tens of m).
  const PoolSpec p = long_trapezoid(20000.0, 200);
  const double yn = normal_depth(0.7, 1.0, 1.5, 0.014, 0.002);
  const BackwaterProfile profile = backwater_profile(p, 0.7, 0.9);
  EXPECT_NEAR(profile.start_depth, yn, 1e-6);
  EXPECT_NEAR(profile.cell_depth.front(), yn, 1e-6);
  EXPECT_NEAR(profile.end_depth, 0.9, 0.0);
  for (std::size_t i = 1; i < profile.cell_depth.size(); ++i) {
    EXPECT_GE(profile.cell_depth[i], profile.cell_depth[i - 1]) << "M1: depth grows downstream";
  }
}

TEST(Backwater, LongChannelReachesTheManningNormalDepthFromBelow) {
  // M2 curve: end depth between critical (~0.3 m) and normal depth (~0.37 m).
  const PoolSpec p = long_trapezoid(20000.0, 200);
  const double yn = normal_depth(0.7, 1.0, 1.5, 0.014, 0.002);
  const BackwaterProfile profile = backwater_profile(p, 0.7, 0.35);
  EXPECT_NEAR(profile.start_depth, yn, 1e-6);
}

TEST(Backwater, AnOfftakeLowersTheUpstreamNormalDepthToThatOfTheLargerFlow) {
  // 10 km at 0.7 m³/s upstream of an offtake of 0.3 m³/s, then 10 km at 0.4 m³/s; a milder
  // slope keeps the upstream M2 curve subcritical. Decay length ~0.3 km: 10 km is ~30 of them.
  PoolSpec p = long_trapezoid(20000.0, 200, 0.0005);
  p.offtakes.push_back({10000.0, 0.3});
  const BackwaterProfile profile = backwater_profile(p, 0.7, 0.9);
  EXPECT_NEAR(profile.start_depth, normal_depth(0.7, 1.0, 1.5, 0.014, 0.0005), 1e-6);
  EXPECT_NEAR(profile.cell_depth[150], normal_depth(0.4, 1.0, 1.5, 0.014, 0.0005), 1e-6);
}

TEST(Backwater, ATargetBelowCriticalDepthIsRefusedNamingThePool) {
  const PoolSpec p = long_trapezoid(2000.0, 20);
  try {
    backwater_profile(p, 0.7, 0.2);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pool 'long'"), std::string::npos) << e.what();
  }
}

TEST(GateOpening, InvertsSwameesFreeFlowFormula) {
  // Free flow: q = 0.864 a sqrt(g y1) ((y1 − a)/(y1 + 15 a))^0.072 (Swamee 1992), here by hand.
  GateSpec g;
  g.width_m = 1.5;
  const double y1 = 0.9, y3 = 0.3, q = 0.7;
  const double a = gate_opening_for(gate_geometry(g), q, y1, y3, 1.0);
  const double swamee = 1.5 * 0.864 * a * std::sqrt(9.81 * y1) * std::pow((y1 - a) / (y1 + 15.0 * a), 0.072);
  EXPECT_NEAR(swamee, q, 1e-9);
}

TEST(GateOpening, AFlowTheGateCannotPassIsRefused) {
  GateSpec g;
  g.width_m = 0.5;
  EXPECT_THROW(gate_opening_for(gate_geometry(g), 5.0, 0.9, 0.3, 0.5), std::runtime_error);
}

TEST(DesignFlows, EachPoolPassesTheHeadFlowLessTheOfftakesUpstream) {
  Scenario s;
  s.upstream.kind = UpstreamKind::discharge;
  s.upstream.discharge_m3s = 13.7;
  s.downstream.kind = DownstreamKind::pump;
  s.downstream.pump_discharge_m3s = 2.7;
  for (double q : {1.7, 1.8, 2.7, 0.3, 0.2, 0.8, 1.2, 2.3}) {
    PoolSpec p;
    p.offtakes.push_back({p.length_m, q});
    s.pools.push_back(p);
  }
  const auto flows = design_flows(s);
  const double check_flows[] = {12.0, 10.2, 7.5, 7.2, 7.0, 6.2, 5.0, 2.7};  // asce_canals.json
  for (std::size_t i = 0; i < 8; ++i) EXPECT_NEAR(flows[i].outflow, check_flows[i], 1e-9) << "pool " << i + 1;
  s.downstream.pump_discharge_m3s = 3.0;  // 0.3 m³/s more than the head flow brings
  EXPECT_THROW(design_flows(s), InputError);
}

TEST(ResolveDesign, HeadGateOpeningPassesTheOfftakesFromTheSupplyLevel) {
  // A 1.5 m supply level feeds one pool through an automatic head gate; the pool's orifice takes
  // 0.5 m³/s and the end is closed, so the head gate must pass 0.5 m³/s. The gate flows free
  // (y3 ~ 0.45 m), so Swamee's free-flow formula, written out here, must give 0.5 m³/s.
  Scenario s;
  s.source = "test";
  s.upstream.kind = UpstreamKind::level;
  s.upstream.level_m = 1.5;
  GateSpec head;
  head.width_m = 1.0;
  head.max_opening_m = 1.0;
  head.auto_opening = true;
  s.head_gate = head;
  PoolSpec p = long_trapezoid(1000.0, 20, 0.001);
  p.target_depth_m = 0.9;
  OfftakeSpec outlet;
  outlet.x_m = 1000.0;
  outlet.discharge_m3s = 0.5;
  outlet.kind = OfftakeKind::orifice;
  p.offtakes.push_back(outlet);
  s.pools.push_back(p);
  s.downstream.kind = DownstreamKind::closed;
  const Scenario r = resolve_design(s);
  const double a = r.head_gate->opening_m, y1 = 1.5;
  EXPECT_FALSE(r.head_gate->auto_opening);
  EXPECT_NEAR(0.864 * a * std::sqrt(9.81 * y1) * std::pow((y1 - a) / (y1 + 15.0 * a), 0.072), 0.5, 1e-9);
  // The orifice sits at the pool's end (x_m = length_m): it delivers its design discharge at the
  // target depth there.
  EXPECT_NEAR(r.pools[0].offtakes[0].coefficient * std::sqrt(0.9), 0.5, 1e-12);
  // A side weir (exponent 3/2) with its crest 0.3 m above the bed is sized on the same state:
  // K 0.6^1.5 = 0.5 m³/s.
  s.pools[0].offtakes[0].exponent = 1.5;
  s.pools[0].offtakes[0].invert_m = 0.3;
  EXPECT_NEAR(resolve_design(s).pools[0].offtakes[0].coefficient * std::pow(0.6, 1.5), 0.5, 1e-12);
}

}  // namespace
}  // namespace canalsim::scenarios
