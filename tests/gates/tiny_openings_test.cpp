// The gate laws stay finite for every opening in their documented range, down to openings that
// round to zero (a command of 1e-320 mm), where the law's 1/a terms could overflow to inf and NaN.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "gates/sluice_gate.hpp"

namespace canalsim::gates {
namespace {

TEST(TinyOpenings, EveryFigureOfTheLawIsFiniteDownToTheSmallestDouble) {
  const double denormal = std::numeric_limits<double>::denorm_min();
  for (const GateLaw law : {GateLaw::swamee, GateLaw::simple}) {
    SluiceGateOptions options;
    options.law = law;
    const SluiceGate gate(options);
    for (const double a : {denormal, 1e-320, 1e-310, 1e-300, 1e-100, 1e-13, 1e-12, 1e-9, 1e-6}) {
      for (const double y3 : {0.0, 0.02, 0.0599, 0.06, 0.07}) {
        const GateFlow f = gate.evaluate(0.06, y3, a);
        EXPECT_TRUE(std::isfinite(f.q) && std::isfinite(f.dq_dy1) && std::isfinite(f.dq_dy3) && std::isfinite(f.dq_da))
            << to_string(law) << " a = " << a << " y3 = " << y3 << ": q " << f.q << ", dq/dy1 " << f.dq_dy1
            << ", dq/dy3 " << f.dq_dy3 << ", dq/da " << f.dq_da;
      }
    }
  }
}

// Below a picometre the gate is closed; at a picometre it passes what the free law says, of the
// order a sqrt(g y1) (Swamee 1992: q = 0.864 a sqrt(g y1) ((y1 - a)/(y1 + 15 a))^0.072), so the
// step between them is ~1e-12 m²/s: no physical difference.
TEST(TinyOpenings, ClosingBelowAPicometreIsAStepOfAPicometreOfFlow) {
  const SluiceGate gate{SluiceGateOptions{}};
  const double y1 = 0.06;
  EXPECT_EQ(gate.evaluate(y1, 0.0, 1e-13).q, 0.0);
  const double at = gate.evaluate(y1, 0.0, 1e-12).q;
  EXPECT_NEAR(at, 0.864 * 1e-12 * std::sqrt(9.81 * y1), 1e-14);
  EXPECT_LT(at, 1e-12);
}

}  // namespace
}  // namespace canalsim::gates
