#include "core/format.hpp"

#include <cmath>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>

namespace canalsim {
namespace {

TEST(FormatG, DefaultPrintsWhatAnOstreamPrints) {
  for (double v : {0.05, 1e-9, 60.25, -3.0, 123456789.0, 0.0}) {
    std::ostringstream expected;
    expected << v;
    EXPECT_EQ(format_g(v), expected.str()) << v;
  }
}

TEST(FormatG, TenDigitsSurviveTheRoundTrip) {
  const double v = 0.1234567891;
  EXPECT_EQ(std::stod(format_g(v, 10)), v);
}

TEST(FormatFixed, FixedDecimalsAndNamedNonFiniteValues) {
  EXPECT_EQ(format_fixed(2.0 / 3.0, 3), "0.667");
  EXPECT_EQ(format_fixed(std::numeric_limits<double>::infinity(), 2), "∞");
  EXPECT_EQ(format_fixed(-std::numeric_limits<double>::infinity(), 2), "-∞");
  EXPECT_EQ(format_fixed(std::nan(""), 2), "n/a");
  EXPECT_EQ(format_estimate(std::numeric_limits<double>::infinity(), 0.0), "∞ (± n/a)");
}

TEST(FormatEstimate, TwoSignificantDigitsOfTheDeviationNeverZero) {
  EXPECT_EQ(format_estimate(0.01234, 0.00041), "0.01234 ± 0.00041");
  EXPECT_EQ(format_estimate(12.345, 0.26), "12.35 ± 0.26");
  EXPECT_EQ(format_estimate(1234.5, 37.0), "1234 ± 37");
  EXPECT_EQ(format_estimate(0.5, 0.0), "0.5 (± n/a)");
}

}  // namespace
}  // namespace canalsim
