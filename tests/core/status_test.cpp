// The Options validation convention (core/status.hpp).
#include "core/status.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace canalsim {
namespace {

TEST(Validator, KeepsTheFirstFailureAndNamesItsField) {
  const Status s = Validator()
                       .require(true, "a", 1.0, "anything")
                       .require(false, "max_lag", 0.0, "1..1000")
                       .require(false, "z", "never reported: the first failure wins")
                       .status();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.field(), "max_lag");
  EXPECT_EQ(s.message(), "max_lag = 0: expected 1..1000");
}

TEST(Validator, NaNFailsAConditionWrittenPositively) {
  const double nan = std::nan("");
  const Status s = Validator().require(nan > 0.0, "window_s", nan, "> 0").status();
  EXPECT_FALSE(s);
  EXPECT_EQ(s.message(), "window_s = nan: expected > 0");
}

TEST(Validator, NestedStructsPrefixTheirFields) {
  const Status inner = Validator().require(false, "fir_order", 1.0, "2..1000").status();
  const Status outer = Validator().require(true, "x", "ok").nested("locate", inner).status();
  EXPECT_EQ(outer.field(), "locate.fir_order");
  EXPECT_EQ(outer.message(), "locate.fir_order = 1: expected 2..1000");
  EXPECT_TRUE(Validator().nested("locate", Status::ok()).status().is_ok());
}

}  // namespace
}  // namespace canalsim
