// Sluice-gate laws (gates/sluice_gate.*): Swamee (1992) free and submerged flow, the paper's
// simple laws (eq. 9, 11), regime conditions (8)/(10), y_lc of eq. (23), and the derivatives the
// gate-to-solver Newton coupling uses.
#include "gates/sluice_gate.hpp"

#include <algorithm>
#include <cmath>
#include <gtest/gtest.h>
#include <random>
#include <stdexcept>
#include <vector>

namespace canalsim::gates {
namespace {

constexpr double g = 9.81;

SluiceGate simple_gate() {
  SluiceGateOptions options;
  options.law = GateLaw::simple;
  return SluiceGate(options);
}

// The tailwater depth y3 at which y_lc(y3, a) = y1 (the regime border), by bisection.
double border_tailwater(double y1, double a) {
  double lo = 1e-9, hi = y1;  // y_lc grows with y3
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (limit_condition_level(mid, a) < y1 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// The opening a at which y_lc(y3, a) = y1, by bisection (y_lc falls as a grows).
double border_opening(double y1, double y3) {
  double lo = 1e-6, hi = y1;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (limit_condition_level(y3, mid) > y1 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// --- values ----------------------------------------------------------------------------------

TEST(SwameeFreeFlow, MatchesHandComputedValues) {
  // q = 0.864 a sqrt(g y1) ((y1 - a)/(y1 + 15 a))^0.072 evaluated by hand (Python, g = 9.81).
  const SluiceGate gate;
  EXPECT_NEAR(gate.discharge(0.06, 0.0, 0.025), 0.013821830178676593, 1e-15);
  EXPECT_NEAR(gate.discharge(0.06, 0.0, 0.015), 0.008705577808299024, 1e-15);
  EXPECT_NEAR(gate.discharge(0.06, 0.0, 0.045), 0.022539395663937162, 1e-15);
  EXPECT_NEAR(gate.discharge(1.0, 0.0, 0.2), 0.48200595245369315, 1e-13);
}

TEST(SwameeFreeFlow, AgreesWithThePublishedDischargeCoefficientForm) {
  // Swamee's paper writes q = Cd a sqrt(2 g y1), Cd = 0.611 ((y1 - a)/(y1 + 15 a))^0.072.
  // 0.611 sqrt(2) = 0.86408, not exactly 0.864, so the two forms agree to 1e-4 relative.
  const SluiceGate gate;
  for (double y1 : {0.03, 0.06, 0.2, 1.5}) {
    for (double ratio : {0.05, 0.2, 0.4, 0.6, 0.8}) {
      const double a = ratio * y1;
      const double cd = 0.611 * std::pow((y1 - a) / (y1 + 15.0 * a), 0.072);
      const double published = cd * a * std::sqrt(2.0 * g * y1);
      EXPECT_NEAR(gate.discharge(y1, 0.0, a), published, 1.2e-4 * published) << y1 << ' ' << a;
    }
  }
}

TEST(SwameeFreeFlow, TailwaterBelowTheLimitDoesNotChangeTheDischarge) {
  const SluiceGate gate;
  const double y1 = 0.06, a = 0.03;  // y_lc > 1.05 y3 here: the law's border is Swamee's own
  const double y3_border = border_tailwater(y1, a);
  const double q0 = gate.discharge(y1, 0.0, a);
  for (double y3 : {0.001, 0.01, 0.5 * y3_border, 0.999 * y3_border}) {
    EXPECT_EQ(gate.discharge(y1, y3, a), q0);
    EXPECT_EQ(gate.evaluate(y1, y3, a).regime, GateRegime::free);
  }
}

TEST(SwameeSubmergedFlow, MatchesHandComputedFactor) {
  const SluiceGate gate;
  const double y1 = 0.06, y3 = 0.045, a = 0.02;
  const double y_lc = 0.81 * y3 * std::pow(y3 / a, 0.72);
  ASSERT_GT(y_lc, y1);
  const double factor = std::pow(y1 - y3, 0.7) /
                        (0.32 * std::pow(y_lc - y1, 0.7) + std::pow(y1 - y3, 0.7));
  EXPECT_NEAR(gate.discharge(y1, y3, a), swamee_free_discharge(y1, a) * factor, 1e-16);
  EXPECT_EQ(gate.evaluate(y1, y3, a).regime, GateRegime::submerged);
}

// Zero-head regularisation (SluiceGateOptions::zero_head = h0): the power h^p of the submerged
// law becomes h (h + h0)^(p - 1), by hand here.
SluiceGate regularised(double h0, GateLaw law = GateLaw::swamee) {
  SluiceGateOptions options;
  options.law = law;
  options.zero_head = h0;
  return SluiceGate(options);
}

TEST(ZeroHeadRegularisation, SwameesFactorTakesTheRegularisedPowerOfTheHead) {
  const double y1 = 0.06, y3 = 0.0591, a = 0.043, h0 = 0.002;  // the lab's head gate at op3
  const double head = y1 - y3;
  const double y_lc = std::max(0.81 * y3 * std::pow(y3 / a, 0.72), 1.05 * y3);  // floored here
  const double d = head * std::pow(head + h0, -0.3);
  const double factor = d / (0.32 * std::pow(y_lc - y1, 0.7) + d);
  EXPECT_NEAR(regularised(h0).discharge(y1, y3, a), swamee_free_discharge(y1, a) * factor, 1e-16);
  // Less than the published law, which it approaches for heads well above h0 ((1 - p) h0 / h).
  EXPECT_LT(regularised(h0).discharge(y1, y3, a), 0.9 * SluiceGate{}.discharge(y1, y3, a));
  const double far = regularised(1e-5).discharge(0.06, 0.045, 0.02), published = SluiceGate{}.discharge(0.06, 0.045, 0.02);
  EXPECT_NEAR(far / published, 1.0, 0.3 * 1e-5 / 0.015) << far / published;
  EXPECT_LT(far, published);
}

TEST(ZeroHeadRegularisation, Equation11BecomesLinearInTheHeadBelowH0) {
  const double y1 = 0.06, y3 = 0.0599, a = 0.02, h0 = 0.004;  // head 0.1 mm << h0
  const double head = y1 - y3;
  const double by_hand = 0.6 * a * std::sqrt(2.0 * 9.81) * head / std::sqrt(head + h0);
  EXPECT_NEAR(regularised(h0, GateLaw::simple).discharge(y1, y3, a), by_hand, 1e-15);
  // The slope at zero head is finite: 0.6 a sqrt(2 g) h0^-0.5 per metre of head.
  const GateFlow at_zero = regularised(h0, GateLaw::simple).evaluate(y1, y1, a);
  EXPECT_NEAR(at_zero.dq_dy1, 0.6 * a * std::sqrt(2.0 * 9.81) / std::sqrt(h0), 1e-12);
  EXPECT_EQ(at_zero.q, 0.0);
}

TEST(ZeroHeadRegularisation, KeepsTheDischargeContinuousAtTheBorderAndThroughZeroHead) {
  const SluiceGate gate = regularised(0.003);
  const double y1 = 0.06, a = 0.03;
  const double y3 = border_tailwater(y1, a);
  // F = 1 at the border whatever the head's power: the submerged discharge meets the free one
  // (the margin's power, (y_lc - y1)^0.7, makes the approach steep: 1e-12 m off, ~1e-7 relative).
  const double free = gate.discharge(y1, 0.0, a);
  EXPECT_EQ(gate.discharge(y1, y3 - 1e-12, a), free);
  EXPECT_NEAR(gate.discharge(y1, y3 + 1e-12, a), free, 1e-6 * free);
  EXPECT_LT(gate.discharge(y1, y3 + 1e-12, a), free);
  // Through zero head: linear, so q(+dh) = -q(-dh) (to the rounding of y1 - y3), and both tiny.
  const double up = gate.discharge(0.05, 0.05 - 1e-9, 0.02), down = gate.discharge(0.05, 0.05 + 1e-9, 0.02);
  EXPECT_NEAR(up, -down, 1e-6 * std::abs(up));
  EXPECT_GT(up, 0.0);
  EXPECT_LT(up, 1e-6 * gate.discharge(0.05, 0.0, 0.02));
}

TEST(ZeroHeadRegularisation, OptionIsValidated) {
  SluiceGateOptions options;
  options.zero_head = -0.001;
  EXPECT_NE(options.validate().message().find("zero_head"), std::string::npos);
  options.zero_head = std::nan("");
  EXPECT_FALSE(options.validate());
}

TEST(SimpleLaws, FreeFlowIsPaperEquation9) {
  // q = 0.6 a sqrt(2 g y1) = 0.6 * 0.025 * sqrt(2 * 9.81 * 0.06), by hand.
  EXPECT_NEAR(simple_gate().discharge(0.06, 0.0, 0.025), 0.01627482718802261, 1e-15);
}

TEST(SimpleLaws, SubmergedFlowIsPaperEquation11) {
  // y_lc(0.045, 0.02) = 0.0887 > 0.06: submerged; q = 0.6 * 0.02 * sqrt(2 * 9.81 * 0.015).
  EXPECT_NEAR(simple_gate().discharge(0.06, 0.045, 0.02), 0.006509930875209045, 1e-15);
}

TEST(SimpleLaws, JumpAtTheRegimeBorderUnlikeSwamee) {
  // The paper's laws switch from sqrt(y1) to sqrt(y1 - y3) at the border: a finite jump.
  const double y1 = 0.06, a = 0.03;
  const double y3 = border_tailwater(y1, a);
  const SluiceGate simple = simple_gate();
  const double below = simple.discharge(y1, y3 - 1e-9, a);
  const double above = simple.discharge(y1, y3 + 1e-9, a);
  EXPECT_GT(std::abs(below - above) / below, 0.1);
}

TEST(DischargeMultiplier, ScalesTheLawLinearlyBelowTheSurface) {
  SluiceGateOptions options;
  options.discharge_coefficient_multiplier = 0.9;
  const SluiceGate scaled(options);
  const SluiceGate nominal;
  for (double y3 : {0.0, 0.045, 0.055}) {
    EXPECT_NEAR(scaled.discharge(0.06, y3, 0.02), 0.9 * nominal.discharge(0.06, y3, 0.02), 1e-16);
  }
}

// --- regimes, y_lc ---------------------------------------------------------------------------

TEST(LimitCondition, IsPaperEquation23) {
  // 0.81 * 0.04 * (0.04 / 0.02)^0.72, by hand.
  EXPECT_NEAR(limit_condition_level(0.04, 0.02), 0.053368697918938744, 1e-16);
  EXPECT_TRUE(std::isinf(limit_condition_level(0.04, 0.0)));
  EXPECT_EQ(limit_condition_level(0.0, 0.02), 0.0);
}

TEST(ClassifyRegime, FollowsConditions8And10) {
  // y_lc(0.04, 0.02) = 53.4 mm.
  EXPECT_EQ(classify_regime(0.060, 0.040, 0.020), GateRegime::free);       // 60 > 53.4
  EXPECT_EQ(classify_regime(0.050, 0.040, 0.020), GateRegime::submerged);  // 40 < 50 < 53.4
  EXPECT_EQ(classify_regime(0.040, 0.050, 0.020), GateRegime::submerged);  // reverse head
  EXPECT_EQ(classify_regime(0.060, 0.040, 0.0), GateRegime::closed);
  EXPECT_EQ(classify_regime(0.060, 0.040, 0.070), GateRegime::out_of_water);
}

TEST(ClassifyRegime, AgreesWithTheRegimeTheLawUses) {
  const SluiceGate gate;
  for (double y3 = 0.005; y3 < 0.06; y3 += 0.0025) {
    for (double a = 0.005; a < 0.05; a += 0.0025) {
      // Where the law floors its border at 1.05 y3 (wide-open gate near zero head) it submerges
      // earlier than the paper's condition; see WideOpenGateDischargeFallsContinuouslyToZeroHead.
      if (limit_condition_level(y3, a) < 1.05 * y3 && 0.06 <= 1.05 * y3) continue;
      EXPECT_EQ(gate.evaluate(0.06, y3, a).regime, classify_regime(0.06, y3, a)) << y3 << ' ' << a;
    }
  }
}

// --- continuity ------------------------------------------------------------------------------

// Largest relative change of q between neighbouring points of a fine sweep of one variable.
template <class Discharge>
double max_relative_step(Discharge q, double from, double to, int points) {
  double worst = 0.0;
  double previous = q(from);
  for (int i = 1; i <= points; ++i) {
    const double next = q(from + (to - from) * i / points);
    worst = std::max(worst, std::abs(next - previous) / std::abs(previous));
    previous = next;
  }
  return worst;
}

TEST(SwameeContinuity, DischargeIsContinuousWhenTheTailwaterCrossesTheBorder) {
  const SluiceGate gate;
  const double y1 = 0.06, a = 0.03;
  const double y3 = border_tailwater(y1, a);
  const double q_border = gate.discharge(y1, y3, a);
  // Approaching the border from the submerged side, the gap closes like delta^0.7.
  double previous_gap = 1.0;
  for (double delta : {1e-5, 1e-7, 1e-9, 1e-11}) {
    const double gap = std::abs(gate.discharge(y1, y3 + delta, a) - q_border) / q_border;
    EXPECT_LT(gap, 0.03 * std::pow(delta / 1e-5, 0.7) + 1e-13) << delta;
    EXPECT_LT(gap, previous_gap);
    previous_gap = gap;
  }
  EXPECT_LT(previous_gap, 1e-6);
  // A sweep of 1 mm either side in steps of 1e-8 m (100 nm): no step changes q by more than
  // the Hölder-0.7 bound of one step.
  const auto q_of_y3 = [&](double t) { return gate.discharge(y1, t, a); };
  EXPECT_LT(max_relative_step(q_of_y3, y3 - 1e-3, y3 + 1e-3, 200000), 2e-4);
}

TEST(SwameeContinuity, DischargeIsContinuousWhenTheOpeningCrossesTheBorder) {
  const SluiceGate gate;
  const double y1 = 0.06, y3 = 0.040;
  const double a_border = border_opening(y1, y3);
  ASSERT_GT(a_border, 0.01);  // 17 mm
  ASSERT_LT(a_border, 0.03);
  EXPECT_EQ(gate.evaluate(y1, y3, a_border - 1e-4).regime, GateRegime::submerged);
  EXPECT_EQ(gate.evaluate(y1, y3, a_border + 1e-4).regime, GateRegime::free);
  const auto q_of_a = [&](double t) { return gate.discharge(y1, y3, t); };
  EXPECT_LT(max_relative_step(q_of_a, a_border - 1e-3, a_border + 1e-3, 200000), 2e-4);
  const double q_border = gate.discharge(y1, y3, a_border);
  EXPECT_LT(std::abs(gate.discharge(y1, y3, a_border - 1e-11) - q_border) / q_border, 1e-6);
}

TEST(SwameeContinuity, DischargeIsContinuousAtZeroHead) {
  const SluiceGate gate;
  // q ~ head^0.7 near zero head: 1e-12 m of head passes ~1e-7 of the free discharge.
  const double q_free = gate.discharge(0.05, 0.0, 0.02);
  EXPECT_EQ(gate.discharge(0.05, 0.05, 0.02), 0.0);
  EXPECT_LT(std::abs(gate.discharge(0.05, 0.05 - 1e-12, 0.02)), 1e-6 * q_free);
  EXPECT_LT(std::abs(gate.discharge(0.05, 0.05 + 1e-12, 0.02)), 1e-6 * q_free);
  EXPECT_LT(gate.discharge(0.05, 0.05 + 1e-12, 0.02), 0.0);
}

TEST(GateOutOfWater, PassesCriticalFlowOfTheUpstreamDepth) {
  const SluiceGate gate;
  // q_c = sqrt(g) (2/3 y1)^1.5 at y1 = 0.06, by hand.
  EXPECT_NEAR(critical_discharge(0.06), 0.02505673562138532, 1e-15);
  for (double a : {0.06, 0.07, 0.5}) {
    const GateFlow flow = gate.evaluate(0.06, 0.01, a);
    EXPECT_NEAR(flow.q, 0.02505673562138532, 1e-12) << a;
    EXPECT_EQ(flow.regime, GateRegime::out_of_water);
  }
}

TEST(GateOutOfWater, SwameeLawMeetsCriticalFlowContinuouslyBelowTheSurface) {
  const SluiceGate gate;
  EXPECT_TRUE(gate.reaches_critical_flow());
  EXPECT_NEAR(gate.critical_opening_ratio(), 0.90572, 1e-5);  // bisection in Python
  const double y1 = 0.06;
  const auto q_of_a = [&](double t) { return gate.discharge(y1, 0.0, t); };
  // Sweep the opening from 0.5 y1 to 1.2 y1 through the kink and the surface.
  EXPECT_LT(max_relative_step(q_of_a, 0.5 * y1, 1.2 * y1, 70000), 1e-4);
}

TEST(GateOutOfWater, ReducedCoefficientJumpsByTheDocumentedAmount) {
  SluiceGateOptions options;
  options.discharge_coefficient_multiplier = 0.9;
  const SluiceGate gate(options);
  EXPECT_FALSE(gate.reaches_critical_flow());
  const double y1 = 0.06;
  const double below = gate.discharge(y1, 0.0, y1 - 1e-9);
  const double above = gate.discharge(y1, 0.0, y1);
  // Header comment: (0.5443 - 0.5461 m) / 0.5443 relative, 10 % at m = 0.9.
  EXPECT_NEAR((above - below) / above, (0.54433 - 0.9 * 0.54611) / 0.54433, 1e-4);
}

TEST(SimpleLaws, ReachCriticalFlowAtTheDocumentedOpeningRatio) {
  const SluiceGate gate = simple_gate();
  EXPECT_NEAR(gate.critical_opening_ratio(), std::pow(2.0 / 3.0, 1.5) / (0.6 * std::sqrt(2.0)),
              1e-12);
  EXPECT_NEAR(gate.discharge(0.06, 0.0, 0.059), critical_discharge(0.06), 1e-14);
}

// --- monotonicity, symmetry, closed gate ------------------------------------------------------

TEST(Monotonicity, DischargeGrowsWithOpeningAndUpstreamDepthAndFallsWithTailwater) {
  for (const GateLaw law : {GateLaw::swamee, GateLaw::simple}) {
    SluiceGateOptions options;
    options.law = law;
    const SluiceGate gate(options);
    for (double y1 = 0.02; y1 <= 0.1; y1 += 0.005) {
      for (double y3 = 0.0; y3 < y1; y3 += 0.004) {
        for (double a = 0.001; a <= 0.12; a += 0.001) {
          const double q = gate.discharge(y1, y3, a);
          const double tol = 1e-15;
          EXPECT_GE(gate.discharge(y1, y3, a + 0.0005), q - tol) << y1 << ' ' << y3 << ' ' << a;
          if (law == GateLaw::swamee) {  // the simple laws jump down at the border in y1, y3
            EXPECT_GE(gate.discharge(y1 + 0.0005, y3, a), q - tol) << y1 << ' ' << y3 << ' ' << a;
            EXPECT_LE(gate.discharge(y1, y3 + 0.0005, a), q + tol) << y1 << ' ' << y3 << ' ' << a;
          }
        }
      }
    }
  }
}

TEST(ReverseHead, GivesReverseFlowThatIsExactlyAntisymmetric) {
  const SluiceGate gate;
  for (double a : {0.01, 0.03, 0.08}) {
    for (double y3 : {0.0, 0.03, 0.05}) {
      const GateFlow forward = gate.evaluate(0.06, y3, a);
      const GateFlow backward = gate.evaluate(y3, 0.06, a);
      EXPECT_EQ(backward.q, -forward.q);
      EXPECT_EQ(backward.dq_dy1, -forward.dq_dy3);
      EXPECT_EQ(backward.dq_dy3, -forward.dq_dy1);
      EXPECT_EQ(backward.dq_da, -forward.dq_da);
      EXPECT_TRUE(backward.reverse);
      EXPECT_FALSE(forward.reverse);
    }
  }
}

TEST(ClosedGate, IsAWall) {
  const SluiceGate gate;
  for (double a : {0.0, -0.01}) {
    const GateFlow flow = gate.evaluate(0.06, 0.02, a);
    EXPECT_EQ(flow.q, 0.0);
    EXPECT_EQ(flow.dq_dy1, 0.0);
    EXPECT_EQ(flow.dq_dy3, 0.0);
    EXPECT_EQ(flow.dq_da, 0.0);
    EXPECT_EQ(flow.regime, GateRegime::closed);
  }
  EXPECT_EQ(gate.discharge(0.0, 0.0, 0.02), 0.0);  // dry on both sides
}

TEST(Leakage, ClosedGateLeaksAsASmallOpening) {
  SluiceGateOptions options;
  options.leakage_opening = 0.001;
  const SluiceGate leaky(options);
  const SluiceGate tight;
  EXPECT_NEAR(leaky.discharge(0.06, 0.02, 0.0), tight.discharge(0.06, 0.02, 0.001), 1e-16);
  EXPECT_NEAR(leaky.discharge(0.06, 0.02, 0.01), tight.discharge(0.06, 0.02, 0.011), 1e-16);
  EXPECT_GT(leaky.discharge(0.06, 0.02, 0.0), 0.0);
}

// --- derivatives -----------------------------------------------------------------------------

struct Point {
  double y1, y3, a;
};

// Points away from the kinks (regime border, opening cap, zero head) where central differences
// with step h are meaningful.
std::vector<Point> smooth_points(const SluiceGate& gate, int count) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> depth(0.005, 0.12), opening(0.001, 0.15);
  std::vector<Point> points;
  while (static_cast<int>(points.size()) < count) {
    const Point p{depth(rng), depth(rng), opening(rng)};
    const double high = std::max(p.y1, p.y3), low = std::min(p.y1, p.y3);
    const double a_seen = std::min(p.a, gate.critical_opening_ratio() * high);
    // The flow law's border: Swamee's y_lc, floored at κ y3 (header comment).
    const double y_lc = std::max(limit_condition_level(low, a_seen), gate.options().border_floor_ratio * low);
    if (high - low < 1e-3) continue;                                  // zero head
    if (std::abs(high - y_lc) < 1e-3) continue;                       // regime border
    if (std::abs(p.a - gate.critical_opening_ratio() * high) < 1e-3) continue;  // cap kink
    if (std::abs(p.a - high) < 1e-3) continue;                        // gate at the surface
    points.push_back(p);
  }
  return points;
}

void expect_derivatives_match_central_differences(const SluiceGate& gate) {
  const double h = 1e-7;
  int regimes_seen[4] = {0, 0, 0, 0};
  for (const Point& p : smooth_points(gate, 2000)) {
    const GateFlow flow = gate.evaluate(p.y1, p.y3, p.a);
    ++regimes_seen[static_cast<int>(flow.regime)];
    const double d_y1 = (gate.discharge(p.y1 + h, p.y3, p.a) - gate.discharge(p.y1 - h, p.y3, p.a)) / (2 * h);
    const double d_y3 = (gate.discharge(p.y1, p.y3 + h, p.a) - gate.discharge(p.y1, p.y3 - h, p.a)) / (2 * h);
    const double d_a = (gate.discharge(p.y1, p.y3, p.a + h) - gate.discharge(p.y1, p.y3, p.a - h)) / (2 * h);
    const double scale = std::abs(flow.dq_dy1) + std::abs(flow.dq_dy3) + std::abs(flow.dq_da) + 1e-12;
    EXPECT_NEAR(flow.dq_dy1, d_y1, 1e-5 * scale) << p.y1 << ' ' << p.y3 << ' ' << p.a;
    EXPECT_NEAR(flow.dq_dy3, d_y3, 1e-5 * scale) << p.y1 << ' ' << p.y3 << ' ' << p.a;
    EXPECT_NEAR(flow.dq_da, d_a, 1e-5 * scale) << p.y1 << ' ' << p.y3 << ' ' << p.a;
  }
  EXPECT_GT(regimes_seen[static_cast<int>(GateRegime::free)], 50);
  EXPECT_GT(regimes_seen[static_cast<int>(GateRegime::submerged)], 50);
  EXPECT_GT(regimes_seen[static_cast<int>(GateRegime::out_of_water)], 50);
}

TEST(Derivatives, SwameeMatchCentralDifferencesInEveryRegime) {
  expect_derivatives_match_central_differences(SluiceGate{});
}

TEST(Derivatives, SimpleLawsMatchCentralDifferencesInEveryRegime) {
  expect_derivatives_match_central_differences(simple_gate());
}

TEST(Derivatives, ScaledLawWithLeakageMatchesCentralDifferences) {
  SluiceGateOptions options;
  options.discharge_coefficient_multiplier = 0.93;
  options.leakage_opening = 0.0005;
  expect_derivatives_match_central_differences(SluiceGate(options));
}

TEST(Derivatives, RegularisedNearZeroHeadMatchCentralDifferences) {
  SluiceGateOptions options;
  options.zero_head = 0.002;
  expect_derivatives_match_central_differences(SluiceGate(options));
  options.law = GateLaw::simple;
  expect_derivatives_match_central_differences(SluiceGate(options));
}

TEST(Derivatives, AreFiniteWithTheRightSignAtZeroHeadAndAtTheBorder) {
  const SluiceGate gate;
  const GateFlow zero_head = gate.evaluate(0.05, 0.05, 0.02);
  EXPECT_TRUE(std::isfinite(zero_head.dq_dy1));
  EXPECT_GT(zero_head.dq_dy1, 0.0);
  EXPECT_LT(zero_head.dq_dy3, 0.0);
  const double y3 = border_tailwater(0.06, 0.03);
  const GateFlow border = gate.evaluate(0.06, y3 + 1e-12, 0.03);
  EXPECT_TRUE(std::isfinite(border.dq_dy1));
  EXPECT_GT(border.dq_dy1, 0.0);
}

// --- options ---------------------------------------------------------------------------------

TEST(SluiceGateOptions, ValidationNamesTheFieldAndItsRange) {
  SluiceGateOptions options;
  EXPECT_TRUE(options.validate());
  options.discharge_coefficient_multiplier = -1.0;
  EXPECT_NE(options.validate().message().find("discharge_coefficient_multiplier = -1: expected a value in (0, 10]"),
            std::string::npos);
  options = {};
  options.leakage_opening = -0.1;
  EXPECT_NE(options.validate().message().find("leakage_opening"), std::string::npos);
  EXPECT_THROW(SluiceGate{options}, std::invalid_argument);
}

}  // namespace
}  // namespace canalsim::gates

namespace canalsim::gates {
namespace {

// A gate opened wider than ~0.75 of the tailwater depth has y_lc < y3: Swamee's condition alone
// would call the flow free right up to zero head and then jump to reverse flow. The law's border
// is floored at 1.05 y3 so the discharge falls continuously to zero (the paper's regime
// classification keeps the published condition).
TEST(SwameeContinuity, WideOpenGateDischargeFallsContinuouslyToZeroHead) {
  const SluiceGate gate;
  const double y1 = 0.060, a = 0.045;
  ASSERT_LT(limit_condition_level(0.0599, a), y1) << "the case must be one the floor is for";
  EXPECT_EQ(classify_regime(y1, 0.0599, a), GateRegime::free);      // the paper's condition
  EXPECT_EQ(gate.evaluate(y1, 0.0599, a).regime, GateRegime::submerged);  // the flow law
  EXPECT_NEAR(gate.discharge(y1, y1, a), 0.0, 1e-15);
  EXPECT_GT(gate.discharge(y1, 0.057, a), 0.0);
  EXPECT_LT(gate.discharge(y1, 0.0605, a), 0.0);
  // Through the floored border (y3 = y1/1.05) and zero head: the largest change between
  // neighbouring points shrinks like step^0.7 (Hölder continuity), where a jump would not shrink.
  const double q_free = gate.discharge(y1, 0.0, a);
  auto worst_step = [&](double step) {
    double worst = 0.0;
    for (double kink : {y1 / 1.05, y1}) {
      double previous = gate.discharge(y1, kink - 1000 * step, a);
      for (int i = -999; i <= 1000; ++i) {
        const double q = gate.discharge(y1, kink + i * step, a);
        worst = std::max(worst, std::abs(q - previous) / q_free);
        previous = q;
      }
    }
    return worst;
  };
  const double coarse = worst_step(1e-7), fine = worst_step(1e-9);
  EXPECT_LT(fine, 0.1 * coarse);  // 100^-0.7 = 0.04 expected
  EXPECT_LT(fine, 1e-4);
}

}  // namespace
}  // namespace canalsim::gates

namespace canalsim::gates {
namespace {

// --- separate submerged coefficient ------------------------------------------------------------

SluiceGate swamee_with(double free_multiplier, double submerged_multiplier) {
  SluiceGateOptions options;
  options.discharge_coefficient_multiplier = free_multiplier;
  options.submerged_discharge_coefficient_multiplier = submerged_multiplier;
  return SluiceGate(options);
}

TEST(SubmergedMultiplier, SwameeBlendsItWithTheSubmergenceFactorByHand) {
  // q = m_f q_f F (rho + (1 - rho) F), rho = m_s / m_f, F by hand as in MatchesHandComputedFactor.
  const double y1 = 0.06, y3 = 0.045, a = 0.02;
  const double y_lc = 0.81 * y3 * std::pow(y3 / a, 0.72);
  const double factor = std::pow(y1 - y3, 0.7) / (0.32 * std::pow(y_lc - y1, 0.7) + std::pow(y1 - y3, 0.7));
  const double rho = 1.1 / 0.9;
  EXPECT_NEAR(swamee_with(0.9, 1.1).discharge(y1, y3, a),
              0.9 * swamee_free_discharge(y1, a) * factor * (rho + (1.0 - rho) * factor), 1e-16);
}

TEST(SubmergedMultiplier, LeavesFreeFlowAndTheBorderToTheFreeMultiplier) {
  const SluiceGate split = swamee_with(0.9, 1.2), plain = swamee_with(0.9, 0.9);
  EXPECT_EQ(split.discharge(0.06, 0.01, 0.02), plain.discharge(0.06, 0.01, 0.02));  // free
  // Continuous across the border: the change over a step across it shrinks with the step as
  // Swamee's own law does (its factor varies as (y_lc - y1)^0.7 there), i.e. no jump.
  const double y3 = border_tailwater(0.06, 0.02);
  for (double step : {1e-6, 1e-9, 1e-12}) {
    const double split_change = std::abs(split.discharge(0.06, y3 + step, 0.02) - split.discharge(0.06, y3 - step, 0.02));
    const double plain_change = std::abs(plain.discharge(0.06, y3 + step, 0.02) - plain.discharge(0.06, y3 - step, 0.02));
    EXPECT_LE(split_change, 1.5 * plain_change + 1e-18) << step;
  }
  // Deeply drowned (F -> 0) the ratio of the two tends to m_s / m_f.
  const double drowned = 0.06 - 1e-7;
  EXPECT_NEAR(split.discharge(0.06, drowned, 0.02) / plain.discharge(0.06, drowned, 0.02), 1.2 / 0.9, 1e-3);
}

TEST(SubmergedMultiplier, EqualToTheFreeOneIsSwameeToTheLastBit) {
  const SluiceGate same = swamee_with(1.0, 1.0), published;
  for (double y3 : {0.03, 0.045, 0.055, 0.0599}) EXPECT_EQ(same.discharge(0.06, y3, 0.02), published.discharge(0.06, y3, 0.02));
}

TEST(SubmergedMultiplier, SimpleSubmergedLawUsesItAlone) {
  SluiceGateOptions options;
  options.law = GateLaw::simple;
  options.discharge_coefficient_multiplier = 0.9;
  options.submerged_discharge_coefficient_multiplier = 1.1;
  // Eq. (11) with Cd = 1.1 * 0.6 (SubmergedFlowIsPaperEquation11 with m = 1.1).
  EXPECT_NEAR(SluiceGate(options).discharge(0.06, 0.045, 0.02), 1.1 * 0.006509930875209045, 1e-15);
}

TEST(SubmergedMultiplier, DerivativesMatchCentralDifferences) {
  expect_derivatives_match_central_differences(swamee_with(0.93, 1.12));
  expect_derivatives_match_central_differences(swamee_with(1.05, 0.85));
}

TEST(SubmergedMultiplier, OutOfRangeIsRejectedNamingTheField) {
  SluiceGateOptions options;
  options.submerged_discharge_coefficient_multiplier = -0.5;
  EXPECT_NE(options.validate().message().find("submerged_discharge_coefficient_multiplier"), std::string::npos);
}

// --- a discharge coefficient varying with the opening ------------------------------------------

SluiceGate rated_gate(double beta, double gamma, double reference, GateLaw law = GateLaw::swamee) {
  SluiceGateOptions options;
  options.law = law;
  options.opening_exponent = beta;
  options.opening_curvature = gamma;
  options.reference_opening = reference;
  return SluiceGate(options);
}

TEST(OpeningRating, MultipliesTheLawByItsClosedFormInEveryRegime) {
  // c(a) = exp(β x + γ x²), x = ln(a / a_ref), computed here by hand, against the published law.
  const double beta = 0.12, gamma = -0.07, reference = 0.03;
  for (const GateLaw law : {GateLaw::swamee, GateLaw::simple}) {
    SluiceGateOptions plain_options;
    plain_options.law = law;
    const SluiceGate rated = rated_gate(beta, gamma, reference, law), plain(plain_options);
    for (const double a : {0.008, 0.015, 0.03, 0.037}) {  // below the simple law's cap, 0.641 y1
      const double x = std::log(a / reference);
      const double c = std::exp(beta * x + gamma * x * x);
      for (const double y3 : {0.005, 0.04, 0.055}) {  // free, submerged, nearly drowned
        EXPECT_NEAR(rated.discharge(0.06, y3, a), c * plain.discharge(0.06, y3, a), 1e-15) << a << ' ' << y3;
      }
    }
  }
}

TEST(OpeningRating, AtItsReferenceOpeningAndWithoutExponentsIsThePublishedLaw) {
  const SluiceGate published;
  EXPECT_EQ(rated_gate(0.0, 0.0, 0.01).discharge(0.06, 0.045, 0.02), published.discharge(0.06, 0.045, 0.02));
  EXPECT_NEAR(rated_gate(0.3, -0.2, 0.02).discharge(0.06, 0.045, 0.02), published.discharge(0.06, 0.045, 0.02), 1e-17);
}

TEST(OpeningRating, DerivativesMatchCentralDifferences) {
  expect_derivatives_match_central_differences(rated_gate(0.15, -0.08, 0.025));
  expect_derivatives_match_central_differences(rated_gate(-0.2, 0.1, 0.01, GateLaw::simple));
}

TEST(OpeningRating, OutOfRangeIsRejectedNamingTheField) {
  SluiceGateOptions options;
  options.opening_exponent = 2.5;
  EXPECT_NE(options.validate().message().find("opening_exponent = 2.5: expected a value in [-2, 2]"), std::string::npos);
  options = {};
  options.reference_opening = 0.0;
  EXPECT_NE(options.validate().message().find("reference_opening"), std::string::npos);
}

}  // namespace
}  // namespace canalsim::gates

namespace canalsim::gates {
namespace {

// --- the floor of the regime border ------------------------------------------------------------

SluiceGate floored_at(double kappa) {
  SluiceGateOptions options;
  options.border_floor_ratio = kappa;
  return SluiceGate(options);
}

// A wide-open gate (the lab's head gate at op3/op4: 45 mm under 60 mm) has Swamee's y_lc below
// the tail; its border is κ y3, so Swamee's factor takes S = (κ y3 − y1)^0.7, by hand here, and
// the flow is the free one once the head passes (κ − 1) y3.
TEST(RegimeBorderFloor, SetsSwameesSubmergenceFactorOfAWideOpenGateByHand) {
  const double y1 = 0.060, a = 0.045;
  for (const double kappa : {1.02, 1.035, 1.05, 1.2}) {
    const SluiceGate gate = floored_at(kappa);
    for (const double y3 : {y1 - 5e-4, 0.5 * (y1 + y1 / kappa), y1 / kappa + 1e-5}) {  // under the floor
      ASSERT_LT(limit_condition_level(y3, a), kappa * y3) << "the case must be one the floor is for";
      const double D = std::pow(y1 - y3, 0.7), S = std::pow(kappa * y3 - y1, 0.7);
      EXPECT_NEAR(gate.discharge(y1, y3, a), swamee_free_discharge(y1, a) * D / (0.32 * S + D), 1e-15)
          << kappa << ' ' << y3;
      EXPECT_EQ(gate.evaluate(y1, y3, a).regime, GateRegime::submerged);
    }
    const double freed = y1 / kappa - 1e-4;  // head above (κ − 1) y3
    EXPECT_EQ(gate.discharge(y1, freed, a), swamee_free_discharge(y1, a)) << kappa;
    EXPECT_EQ(gate.evaluate(y1, freed, a).regime, GateRegime::free);
  }
  // Where Swamee's border lies above the floor (a gate 20 mm open) the floor changes nothing.
  EXPECT_EQ(floored_at(1.2).discharge(0.06, 0.045, 0.02), SluiceGate{}.discharge(0.06, 0.045, 0.02));
}

TEST(RegimeBorderFloor, DerivativesMatchCentralDifferences) {
  expect_derivatives_match_central_differences(floored_at(1.02));
  expect_derivatives_match_central_differences(floored_at(1.3));
}

TEST(RegimeBorderFloor, OutOfRangeIsRejectedNamingTheField) {
  SluiceGateOptions options;
  options.border_floor_ratio = 1.0;  // a border at the tail: no submerged flow at all
  EXPECT_NE(options.validate().message().find("border_floor_ratio = 1: expected a value in (1, 2]"), std::string::npos)
      << options.validate().message();
  EXPECT_THROW(SluiceGate{options}, std::invalid_argument);
}

}  // namespace
}  // namespace canalsim::gates
