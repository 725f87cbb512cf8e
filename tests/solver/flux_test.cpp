// Flux kernels (solver/flux.hpp): consistency, upwinding, symmetry and dry states.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/flux.hpp"

namespace canalsim::solver {
namespace {

constexpr double g = 9.81;

// Rectangular unit-width point state of depth h and velocity u.
PointState rect(double h, double u) { return {h, h > 0.0 ? u : 0.0, 0.5 * g * h * h, std::sqrt(g * h)}; }

TEST(HllFlux, IsConsistentWithThePhysicalFluxForEqualStates) {
  for (const FluxKernel kernel : {&hll_flux, &rusanov_flux}) {
    const PointState s = rect(0.8, 0.5);
    const Flux f = kernel(s, s), exact = physical_flux(s);
    EXPECT_NEAR(f.mass, exact.mass, 1e-14);
    EXPECT_NEAR(f.momentum, exact.momentum, 1e-13);
  }
}

TEST(HllFlux, LakeAtRestGivesZeroMassFluxAndTheHydrostaticPressure) {
  const Flux f = hll_flux(rect(1.0, 0.0), rect(1.0, 0.0));
  EXPECT_EQ(f.mass, 0.0);
  EXPECT_NEAR(f.momentum, 0.5 * g, 1e-15);
}

TEST(HllFlux, SupercriticalFlowIsFullyUpwinded) {
  const PointState l = rect(0.2, 5.0), r = rect(0.25, 4.5);  // u > c on both sides
  const Flux f = hll_flux(l, r), fl = physical_flux(l);
  EXPECT_DOUBLE_EQ(f.mass, fl.mass);
  EXPECT_DOUBLE_EQ(f.momentum, fl.momentum);
  const Flux b = hll_flux(rect(0.25, -4.5), rect(0.2, -5.0)), fr = physical_flux(rect(0.2, -5.0));
  EXPECT_DOUBLE_EQ(b.mass, fr.mass);
}

TEST(HllFlux, MirrorStatesGiveZeroMassFlux) {
  const Flux f = hll_flux(rect(0.6, 0.7), rect(0.6, -0.7));
  EXPECT_NEAR(f.mass, 0.0, 1e-15);
  EXPECT_GT(f.momentum, 0.5 * g * 0.36);  // a wall pushes back harder against incoming flow
}

TEST(HllFlux, TwoDryStatesGiveZeroFluxWithoutNaN) {
  const Flux f = hll_flux(rect(0.0, 0.0), rect(0.0, 0.0));
  EXPECT_EQ(f.mass, 0.0);
  EXPECT_EQ(f.momentum, 0.0);
  EXPECT_EQ(f.max_speed, 0.0);
}

TEST(HllFlux, WetStateNextToDryUsesTheDryFrontSpeed) {
  // Ritter: the front moves at u + 2c; the flux out of the wet side is positive.
  const Flux f = hll_flux(rect(1.0, 0.0), rect(0.0, 0.0));
  EXPECT_GT(f.mass, 0.0);
  EXPECT_NEAR(f.max_speed, 2.0 * std::sqrt(g), 1e-14);
}

TEST(RusanovFlux, IsMoreDiffusiveThanHllAcrossAJump) {
  const PointState l = rect(1.0, 0.0), r = rect(0.5, 0.0);
  EXPECT_GE(rusanov_flux(l, r).mass, hll_flux(l, r).mass);
}

}  // namespace
}  // namespace canalsim::solver
