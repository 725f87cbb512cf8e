// Riemann invariants and the face-state solve a structure uses (solver/characteristics.*).
#include <gtest/gtest.h>

#include <cmath>

#include "solver/characteristics.hpp"

namespace canalsim::solver {
namespace {

constexpr double g = 9.81;

InteriorState cell(const Section& s, double h, double u) { return {s.area(h), s.area(h) * u, h, 0.0}; }

TEST(Characteristics, OutgoingInvariantIsUPlusTwoCDownstreamAndUMinusTwoCUpstream) {
  const Section s{0.08, 0.0};
  const double c = std::sqrt(g * 0.06);
  EXPECT_NEAR(outgoing_invariant(s, g, End::downstream, cell(s, 0.06, 0.1)), 0.1 + 2.0 * c, 1e-14);
  EXPECT_NEAR(outgoing_invariant(s, g, End::upstream, cell(s, 0.06, 0.1)), 0.1 - 2.0 * c, 1e-14);
}

TEST(Characteristics, VelocityFromInvariantInvertsTheInvariantAtTheSameDepth) {
  const Section s{2.0, 1.5};
  for (End end : {End::upstream, End::downstream}) {
    const double w = outgoing_invariant(s, g, end, 0.7, 0.3);
    EXPECT_NEAR(velocity_from_invariant(s, g, end, w, 0.7), 0.3, 1e-14);
  }
}

TEST(Characteristics, SupercriticalOutflowIsDetectedOnlyTowardsTheFace) {
  const Section s{1.0, 0.0};
  EXPECT_TRUE(is_supercritical_outflow(s, g, End::downstream, cell(s, 0.1, 2.0)));
  EXPECT_FALSE(is_supercritical_outflow(s, g, End::upstream, cell(s, 0.1, 2.0)));
  EXPECT_TRUE(is_supercritical_outflow(s, g, End::upstream, cell(s, 0.1, -2.0)));
  EXPECT_FALSE(is_supercritical_outflow(s, g, End::downstream, cell(s, 1.0, 0.5)));
}

TEST(Characteristics, FaceStateFluxPassesExactlyTheGivenDischarge) {
  const Section s{2.0, 1.5};
  const Flux f = face_state_flux(s, g, 0.7, 1.234567);
  EXPECT_EQ(f.mass, 1.234567);
  EXPECT_NEAR(f.momentum, 1.234567 * 1.234567 / s.area(0.7) + g * s.pressure_integral(0.7), 1e-12);
}

TEST(SolveFaceState, ConstantInflowAtTheUpstreamEndMatchesTheClosedFormInvariant) {
  // Rectangle, upstream end: Q/(b h) − 2 sqrt(g h) = u_i − 2 c_i, solved here by bisection.
  const Section s{1.0, 0.0};
  const InteriorState in = cell(s, 0.5, 0.2);
  const double q = 1.0, w = 0.2 - 2.0 * std::sqrt(g * 0.5);
  double lo = 1e-6, hi = 10.0;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    ((q / mid - 2.0 * std::sqrt(g * mid) - w) > 0.0 ? lo : hi) = mid;
  }
  const FaceState face = solve_face_state(s, g, End::upstream, in, [q](double) { return q; });
  ASSERT_TRUE(face.found);
  EXPECT_NEAR(face.depth, lo, 1e-10);
  EXPECT_EQ(face.discharge, q);
}

TEST(SolveFaceState, GateLikeLawAtTheDownstreamEndTakesTheSubcriticalRoot) {
  // A free-flow orifice Q = Cd a b sqrt(2 g h_b) at a downstream end, trapezoidal channel.
  const Section s{0.5, 1.0};
  const InteriorState in = cell(s, 0.6, 0.3);
  const auto law = [](double h) { return 0.6 * 0.05 * 0.5 * std::sqrt(2.0 * g * h); };
  const FaceState face = solve_face_state(s, g, End::downstream, in, law);
  ASSERT_TRUE(face.found);
  const double w = outgoing_invariant(s, g, End::downstream, in);
  const double u_b = velocity_from_invariant(s, g, End::downstream, w, face.depth);
  EXPECT_NEAR(s.area(face.depth) * u_b, law(face.depth), 1e-9);
  EXPECT_LT(std::abs(u_b), s.celerity(face.depth, g));  // tranquil branch
  EXPECT_NEAR(face.discharge, law(face.depth), 1e-15);
}

TEST(SolveFaceState, ReportsNotFoundWhenTheInteriorCannotSupplyTheDischarge) {
  const Section s{1.0, 0.0};
  const FaceState face = solve_face_state(s, g, End::downstream, cell(s, 0.01, 0.0), [](double) { return 50.0; });
  EXPECT_FALSE(face.found);
}

}  // namespace
}  // namespace canalsim::solver
