// Level-dependent outlets of a reach (solver/reach.hpp): a closed rectangular tank drained by an
// orifice Q = K sqrt(h) follows the closed form of Torricelli's draining,
//   A_s dh/dt = −K sqrt(h)  ⇒  sqrt(h(t)) = sqrt(h0) − K t / (2 A_s),
// a weir outlet Q = K h^(3/2) its own closed form, and the volume balance books the outlet as
// lateral outflow.
#include <cmath>
#include <gtest/gtest.h>
#include <memory>
#include <stdexcept>

#include "solver/canal.hpp"
#include "testing/reaches.hpp"

namespace canalsim::solver {
namespace {

// A 10 m reach of 10 cells, 1 m deep at rest, walls at both ends.
void walled_tank(Canal& canal, const Section& section) {
  ASSERT_TRUE(canal.add_reach(testing::uniform_reach(10.0, 10, section, 0.0, 1.0)));
  ASSERT_TRUE(canal.set_boundary(0, End::upstream, std::make_shared<WallBoundary>()));
  ASSERT_TRUE(canal.set_boundary(0, End::downstream, std::make_shared<WallBoundary>()));
}

// The walled tank drained through its outlet: the mean depth within 0.5 mm of the closed form's
// `depth`, the outlet passing `law_discharge` (its law at its cell's depth), and the volume that
// left booked as lateral outflow with the balance closed to round-off.
void expect_drained(const Canal& canal, double depth, double law_discharge) {
  const double mean_depth = canal.reach(0).volume() / 10.0;
  EXPECT_NEAR(mean_depth, depth, 5e-4);
  EXPECT_NEAR(canal.reach(0).outlet_discharge(0), law_discharge, 1e-15);
  const VolumeBalance b = canal.total_balance();
  EXPECT_NEAR(b.lateral, -(10.0 - canal.reach(0).volume()), 1e-9);
  EXPECT_LT(b.relative_error(), 1e-12);
}

TEST(Outlets, AnOrificeDrainsAClosedTankAsTorricelliSays) {
  Canal canal;
  walled_tank(canal, {1.0, 0.0});
  const double k = 0.01;  // m^2.5/s: 10 L/s at 1 m, the tank (10 m²) falls ~1 mm/s
  EXPECT_EQ(canal.reach(0).add_outlet(9, k, 0.0), 0);
  ASSERT_TRUE(canal.advance_to(500.0));
  // The tank is short (waves cross it in ~3 s): its level stays nearly flat while it drains. The
  // outlet cell stands a little below the mean (the flow towards the outlet draws it down), so
  // the tank drains slightly slower than the closed form: 0.26 mm of 0.56 m after 500 s.
  const double expected_root = 1.0 - k * 500.0 / (2.0 * 10.0);
  expect_drained(canal, expected_root * expected_root, k * std::sqrt(canal.reach(0).depth(9)));
}

// An outlet of exponent 3/2 (a side weir over its invert): A_s dh/dt = −K h^(3/2) integrates to
//   h(t)^(-1/2) = h0^(-1/2) + K t / (2 A_s),
// here 1 + 0.01 · 500 / 20 = 1.25 after 500 s, h = 0.64 m.
TEST(Outlets, AWeirOutletDrainsAClosedTankAsItsClosedFormSays) {
  Canal canal;
  walled_tank(canal, {1.0, 0.0});
  const double k = 0.01;  // m^1.5/s: 10 L/s at 1 m of head
  EXPECT_EQ(canal.reach(0).add_outlet(9, k, 0.0, 1.5), 0);
  ASSERT_TRUE(canal.advance_to(500.0));
  const double expected_inverse_root = 1.0 + k * 500.0 / (2.0 * 10.0);
  // As for the orifice, the outlet cell stands slightly below the mean.
  expect_drained(canal, 1.0 / (expected_inverse_root * expected_inverse_root),
                 k * std::pow(canal.reach(0).depth(9), 1.5));
}

// Below its invert an outlet passes nothing, whatever its exponent; exponents outside [1/2, 3]
// are refused.
TEST(Outlets, AWeirOutletBelowItsCrestIsDryAndBadExponentsAreRefused) {
  Canal canal;
  walled_tank(canal, {1.0, 0.0});
  canal.reach(0).add_outlet(5, 0.05, 1.2, 1.5);  // crest 0.2 m above the 1 m pool
  ASSERT_TRUE(canal.advance_to(30.0));
  EXPECT_EQ(canal.reach(0).outlet_discharge(0), 0.0);
  EXPECT_NEAR(canal.reach(0).volume(), 10.0, 1e-12);
  EXPECT_THROW(canal.reach(0).add_outlet(5, 0.05, 0.0, 0.4), std::invalid_argument);
  EXPECT_THROW(canal.reach(0).add_end_outlet(0.05, 0.0, 3.5), std::invalid_argument);
  EXPECT_THROW(canal.reach(0).add_outlet(5, 0.05, 0.0, std::nan("")), std::invalid_argument);
}

TEST(Outlets, AChangedCoefficientTakesEffectAndZeroStopsTheOutlet) {
  Canal canal;
  walled_tank(canal, {1.0, 1.5});
  canal.reach(0).add_outlet(0, 0.02, 0.2);
  ASSERT_TRUE(canal.advance_to(10.0));
  canal.reach(0).set_outlet_coefficient(0, 0.0);
  ASSERT_TRUE(canal.advance_to(20.0));  // the first stage of this run removes the outlet's share
  const double volume = canal.reach(0).volume();
  ASSERT_TRUE(canal.advance_to(60.0));
  EXPECT_NEAR(canal.reach(0).volume(), volume, 1e-12 * volume);
  for (double q : canal.reach(0).lateral_inflow()) EXPECT_NEAR(q, 0.0, 1e-17);
}

// An offtake at the end face of a reach joined to the next by a link: the volume balance closes,
// the offtake is booked as lateral outflow of its reach (fixed part + orifice, by hand from the
// stage evaluations' sum), and the link passes the same volume out of one reach and into the next.
TEST(EndWithdrawal, ThroughALinkTheBalanceClosesAndTheLinkCarriesOnlyWhatGoesOn) {
  Canal canal;
  for (int k = 0; k < 2; ++k) ASSERT_TRUE(canal.add_reach(testing::uniform_reach(50.0, 25, {1.0, 1.0}, 0.015, 1.0)));
  ASSERT_TRUE(canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(0.6)));
  ASSERT_TRUE(canal.connect(0, 1, std::make_shared<ContinuousLink>()));
  ASSERT_TRUE(canal.set_boundary(1, End::downstream, FixedLevelBoundary::depth(1.0)));
  canal.reach(0).fixed_end_withdrawal() = 0.15;
  const int outlet = canal.reach(0).add_end_outlet(0.1, 0.2);
  ASSERT_TRUE(canal.advance_to(300.0));
  const VolumeBalance total = canal.total_balance(), first = canal.balance(0), second = canal.balance(1);
  EXPECT_LT(total.relative_error(), 1e-12);
  EXPECT_NEAR(total.inflow, 0.6 * 300.0, 1e-9);
  EXPECT_NEAR(first.outflow, second.inflow, 1e-9 * second.inflow);  // the link: out of one, into the other
  // The offtake: at least the fixed 0.15 m³/s and the orifice's K sqrt(h − 0.2) at ~0.8 m head.
  const double q_orifice = canal.reach(0).outlet_discharge(outlet);
  EXPECT_NEAR(q_orifice, 0.1 * std::sqrt(canal.reach(0).depth(24) - 0.2), 2e-3);
  EXPECT_NEAR(first.lateral / 300.0, -(0.15 + q_orifice), 0.01);
  EXPECT_NEAR(second.lateral, 0.0, 0.0);
}

}  // namespace
}  // namespace canalsim::solver
