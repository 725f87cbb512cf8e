// The Bode section's verdict on fractionality (study/bode.hpp) follows its stated rule.
#include <gtest/gtest.h>

#include "study/bode.hpp"

namespace canalsim::study {
namespace {

BodeSection section(double lambda, double error, double integer_error) {
  BodeSection b;
  b.experiment = "op9";
  b.operating_opening_mm = 30.0;
  b.pde_fit.order = lambda;
  b.pde_fit.rms_relative_error = error;
  b.pde_fit.integer_rms_relative_error = integer_error;
  return b;
}

TEST(BodeSection, TheSentenceFollowsTheFractionalityRule) {
  EXPECT_NE(fractionality_sentence(section(0.5, 0.03, 0.09)).find("is fractional in the PRBS band with λ = 0.50"),
            std::string::npos);
  // λ < 0.9 but no better than λ = 1: first order.
  EXPECT_NE(fractionality_sentence(section(0.8, 0.05, 0.06)).find("is a first-order lag"), std::string::npos);
  EXPECT_NE(fractionality_sentence(section(0.97, 0.02, 0.02)).find("is a first-order lag"), std::string::npos);
  // Nothing within 10 %.
  EXPECT_NE(fractionality_sentence(section(0.7, 0.28, 0.29)).find("is not a first-order lag of any order"),
            std::string::npos);
}

}  // namespace
}  // namespace canalsim::study
