// Cross-section geometry (solver/section.*) against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/section.hpp"

namespace canalsim::solver {
namespace {

constexpr double g = 9.81;

TEST(Section, TrapezoidAreaWidthPerimeterAndPressureIntegralMatchClosedForms) {
  const Section s{2.0, 1.5};
  const double h = 0.7;
  EXPECT_DOUBLE_EQ(s.area(h), h * (2.0 + 1.5 * h));
  EXPECT_DOUBLE_EQ(s.top_width(h), 2.0 + 3.0 * h);
  EXPECT_DOUBLE_EQ(s.wetted_perimeter(h), 2.0 + 2.0 * h * std::sqrt(1.0 + 2.25));
  EXPECT_NEAR(s.pressure_integral(h), 2.0 * h * h / 2.0 + 1.5 * h * h * h / 3.0, 1e-15);
}

TEST(Section, DepthInvertsAreaForRectanglesTrapezoidsAndTriangles) {
  for (const Section s : {Section{0.08, 0.0}, Section{2.0, 1.5}, Section{0.0, 1.0}}) {
    for (double h : {0.0, 1e-9, 0.06, 1.0, 25.0}) EXPECT_NEAR(s.depth(s.area(h)), h, 1e-14 * (1.0 + h));
  }
}

TEST(Section, PressureIntegralDerivativeIsTheArea) {
  // dI1/dh = A(h) for a prismatic section: what makes the hydrostatic reconstruction exact.
  const Section s{1.2, 0.8};
  for (double h : {0.1, 0.5, 2.0}) {
    const double d = (s.pressure_integral(h + 1e-6) - s.pressure_integral(h - 1e-6)) / 2e-6;
    EXPECT_NEAR(d, s.area(h), 1e-7);
  }
}

TEST(Section, MeanAreaIsTheDifferenceQuotientOfThePressureIntegral) {
  const Section s{1.2, 0.8};
  const double h1 = 0.3, h2 = 0.9;
  EXPECT_NEAR(s.mean_area(h1, h2), (s.pressure_integral(h2) - s.pressure_integral(h1)) / (h2 - h1), 1e-14);
  EXPECT_NEAR(s.mean_area(h1, h1), s.area(h1), 1e-15);
}

TEST(Section, CelerityIsSqrtOfGTimesHydraulicDepth) {
  EXPECT_NEAR(Section({0.08, 0.0}).celerity(0.06, g), std::sqrt(g * 0.06), 1e-15);
  const Section s{2.0, 1.5};
  EXPECT_NEAR(s.celerity(0.7, g), std::sqrt(g * s.area(0.7) / s.top_width(0.7)), 1e-15);
  EXPECT_EQ(Section({0.0, 1.0}).celerity(0.0, g), 0.0);
}

TEST(Section, CriticalDepthHasFroudeNumberOne) {
  EXPECT_NEAR(Section({1.0, 0.0}).critical_depth(1.53, g), std::cbrt(1.53 * 1.53 / g), 1e-14);
  const Section s{2.0, 1.5};
  const double hc = s.critical_depth(6.0, g);
  const double a = s.area(hc);
  EXPECT_NEAR(36.0 * s.top_width(hc) / (g * a * a * a), 1.0, 1e-12);
}

TEST(Section, CharacteristicIntegralIsTwiceTheCelerityForRectangles) {
  EXPECT_NEAR(Section({0.08, 0.0}).characteristic_integral(0.06, g), 2.0 * std::sqrt(g * 0.06), 1e-15);
}

TEST(Section, CharacteristicIntegralOfATrapezoidMatchesAFineQuadrature) {
  // Φ(h) = ∫_0^h sqrt(g T/A) ds; reference by the midpoint rule in s = h τ² on 200000 panels.
  for (const Section s : {Section{2.0, 1.5}, Section{0.0, 1.0}, Section{0.3, 4.0}}) {
    const double h = 0.8;
    const int n = 200000;
    double ref = 0.0;
    for (int k = 0; k < n; ++k) {
      const double tau = (k + 0.5) / n, d = h * tau * tau;
      ref += std::sqrt(g * s.top_width(d) / s.area(d)) * 2.0 * h * tau / n;
    }
    EXPECT_NEAR(s.characteristic_integral(h, g), ref, 1e-8 * ref);
  }
  // A triangle has Φ = 2 sqrt(2 g h)·... closed form: T/A = 2/h, Φ = ∫ sqrt(2g/s) ds = 2 sqrt(2 g h).
  EXPECT_NEAR(Section({0.0, 1.0}).characteristic_integral(0.8, g), 2.0 * std::sqrt(2.0 * g * 0.8), 1e-12);
}

}  // namespace
}  // namespace canalsim::solver
