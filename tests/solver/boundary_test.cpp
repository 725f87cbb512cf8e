// Built-in boundaries and the continuous link (solver/boundary.*).
#include <gtest/gtest.h>

#include <cmath>

#include "solver/boundary.hpp"

namespace canalsim::solver {
namespace {

constexpr double g = 9.81;

BoundaryInput input(End end, const Section& s, double h, double u, double bed = 0.0) {
  BoundaryInput in;
  in.end = end;
  in.section = s;
  in.gravity = g;
  in.cell = {s.area(h), s.area(h) * u, h, bed};
  in.cell_length = 0.05;
  return in;
}

TEST(WallBoundary, PassesNoMassAndTheHydrostaticForceAtRest) {
  const Section s{0.08, 0.0};
  for (End end : {End::upstream, End::downstream}) {
    const Flux f = WallBoundary().flux(input(end, s, 0.06, 0.0));
    EXPECT_EQ(f.mass, 0.0);
    EXPECT_NEAR(f.momentum, g * s.pressure_integral(0.06), 1e-15);
  }
  EXPECT_EQ(WallBoundary().flux(input(End::downstream, s, 0.06, 0.3)).mass, 0.0);
}

TEST(TransmissiveBoundary, ReturnsThePhysicalFluxOfTheInteriorState) {
  const Section s{1.0, 0.5};
  const Flux f = TransmissiveBoundary().flux(input(End::downstream, s, 0.4, 0.7));
  EXPECT_NEAR(f.mass, s.area(0.4) * 0.7, 1e-15);
  EXPECT_NEAR(f.momentum, s.area(0.4) * 0.49 + g * s.pressure_integral(0.4), 1e-14);
}

TEST(FixedLevelBoundary, AtTheInteriorLevelWithNoFlowIsAtRest) {
  const Section s{2.0, 1.5};
  const Flux p = FixedLevelBoundary::level(1.3)->flux(input(End::downstream, s, 0.8, 0.0, 0.5));
  EXPECT_NEAR(p.mass, 0.0, 1e-15);
  EXPECT_NEAR(p.momentum, g * s.pressure_integral(0.8), 1e-13);
}

TEST(FixedLevelBoundary, LowerOutsideLevelDrawsWaterOutAlongTheCPlusCharacteristic) {
  const Section s{1.0, 0.0};
  const Flux f = FixedLevelBoundary::depth(0.5)->flux(input(End::downstream, s, 0.6, 0.0));
  // u_b = 2 (c_i − c_b), mass flux = h_b u_b.
  EXPECT_NEAR(f.mass, 0.5 * 2.0 * (std::sqrt(g * 0.6) - std::sqrt(g * 0.5)), 1e-13);
}

TEST(FixedLevelBoundary, SupercriticalOutflowIgnoresTheImposedLevel) {
  const Section s{1.0, 0.0};
  const Flux f = FixedLevelBoundary::depth(2.0)->flux(input(End::downstream, s, 0.1, 3.0));
  EXPECT_NEAR(f.mass, 0.3, 1e-15);
}

TEST(FixedDischargeBoundary, PassesExactlyTheImposedDischarge) {
  for (const Section s : {Section{1.0, 0.0}, Section{0.5, 2.0}}) {
    const auto b = FixedDischargeBoundary::constant(0.75);
    EXPECT_EQ(b->flux(input(End::upstream, s, 0.4, 0.1)).mass, 0.75);
    const FixedDischargeBoundary ramp([](double t) { return 0.1 * t; });
    BoundaryInput in = input(End::upstream, s, 0.4, 0.1);
    in.time = 3.0;
    EXPECT_NEAR(ramp.flux(in).mass, 0.3, 1e-15);
  }
}

TEST(CriticalDepthBoundary, RectangularFaceSatisfiesThreeCbEqualsUPlusTwoC) {
  const Section s{1.0, 0.0};
  const double h = 0.5, u = 0.4;
  const Flux f = CriticalDepthBoundary().flux(input(End::downstream, s, h, u));
  const double cb = (u + 2.0 * std::sqrt(g * h)) / 3.0, hb = cb * cb / g;
  EXPECT_NEAR(f.mass, hb * cb, 1e-10);
}

TEST(CriticalDepthBoundary, TrapezoidalFaceIsCriticalOnTheOutgoingCharacteristic) {
  const Section s{0.5, 1.0};
  const double h = 0.5, u = 0.2;
  const Flux f = CriticalDepthBoundary().flux(input(End::downstream, s, h, u));
  // Recover h_b from Q = A c at Fr = 1 and check the invariant.
  double lo = 1e-6, hi = h;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    (s.area(mid) * s.celerity(mid, g) < f.mass ? lo : hi) = mid;
  }
  const double hb = lo;
  EXPECT_NEAR(s.celerity(hb, g) + s.characteristic_integral(hb, g), u + s.characteristic_integral(h, g), 1e-8);
}

TEST(ContinuousLink, SameStateOnBothSidesIsAtRestAndConservesMass) {
  LinkInput in;
  in.upstream_section = in.downstream_section = {1.0, 0.0};
  in.upstream_cell = {0.5, 0.0, 0.5, 0.2};
  in.downstream_cell = {0.7, 0.0, 0.7, 0.0};  // same level 0.7 over a bed step
  const LinkFlux f = ContinuousLink().flux(in);
  EXPECT_NEAR(f.mass, 0.0, 1e-15);
  EXPECT_NEAR(f.momentum_upstream, g * 0.5 * 0.25, 1e-14);
  EXPECT_NEAR(f.momentum_downstream, g * 0.5 * 0.49, 1e-14);
}

}  // namespace
}  // namespace canalsim::solver
