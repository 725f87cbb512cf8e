// Validation of SolverOptions and ReachSpec (solver/options.*): every invalid field is rejected
// with a message that names the field and the allowed range.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "solver/canal.hpp"
#include "solver/options.hpp"

namespace canalsim::solver {
namespace {

ReachSpec valid_reach() {
  ReachSpec spec;
  spec.name = "main";
  spec.length = 5.0;
  spec.cells = 10;
  spec.section = {0.08, 0.0};
  spec.initial_depth.assign(10, 0.06);
  return spec;
}

void expect_rejected(const Status& status, const std::string& field, const std::string& range) {
  EXPECT_FALSE(status.is_ok());
  EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
  EXPECT_NE(status.message().find(range), std::string::npos) << status.message();
}

TEST(SolverOptions, DefaultsAreValid) { EXPECT_TRUE(validate(SolverOptions{})); }

TEST(SolverOptions, CflOutsideZeroToOneIsRejectedNamingTheFieldAndRange) {
  for (double cfl : {0.0, -0.5, 1.5, std::nan("")}) {
    SolverOptions o;
    o.cfl = cfl;
    expect_rejected(validate(o), "SolverOptions::cfl", "(0, 1]");
  }
  SolverOptions o;
  o.cfl = 1.0;
  EXPECT_TRUE(validate(o));
}

TEST(SolverOptions, LimiterThetaGravityDryDepthAndTimeStepAreRangeChecked) {
  SolverOptions o;
  o.limiter_theta = 2.5;
  expect_rejected(validate(o), "limiter_theta", "[1, 2]");
  o = {};
  o.gravity = -9.81;
  expect_rejected(validate(o), "gravity", "(0, inf)");
  o = {};
  o.dry_depth = -1.0;
  expect_rejected(validate(o), "dry_depth", "[0, 0.01]");
  o = {};
  o.max_time_step = 0.0;
  expect_rejected(validate(o), "max_time_step", "(0, inf]");
  o = {};
  o.max_step_retries = -1;
  expect_rejected(validate(o), "max_step_retries", "[0, 60]");
}

TEST(ReachSpec, ValidReachIsAccepted) { EXPECT_TRUE(validate(valid_reach())); }

TEST(ReachSpec, NegativeWidthIsRejectedNamingTheField) {
  ReachSpec s = valid_reach();
  s.section.bottom_width = -0.08;
  expect_rejected(validate(s), "ReachSpec(main)::section.bottom_width", "[0, inf)");
}

TEST(ReachSpec, NegativeSideSlopeAndZeroSectionAreRejected) {
  ReachSpec s = valid_reach();
  s.section.side_slope = -1.0;
  expect_rejected(validate(s), "section.side_slope", "[0, inf)");
  s.section = {0.0, 0.0};
  EXPECT_NE(validate(s).message().find("bottom_width and side_slope are both 0"), std::string::npos);
}

TEST(ReachSpec, NonPositiveLengthAndTooFewCellsAreRejected) {
  ReachSpec s = valid_reach();
  s.length = 0.0;
  expect_rejected(validate(s), "ReachSpec(main)::length", "(0, inf)");
  s = valid_reach();
  s.length = -3.0;
  expect_rejected(validate(s), "length", "(0, inf)");
  s = valid_reach();
  s.cells = 0;
  s.initial_depth.clear();
  expect_rejected(validate(s), "ReachSpec(main)::cells", "[2, inf)");
}

TEST(ReachSpec, NegativeManningCoefficientIsRejected) {
  ReachSpec s = valid_reach();
  s.manning_n = -0.01;
  expect_rejected(validate(s), "ReachSpec(main)::manning_n", "[0, inf)");
}

TEST(ReachSpec, NanInTheInitialStateIsRejectedNamingTheArrayAndCell) {
  ReachSpec s = valid_reach();
  s.initial_depth[3] = std::nan("");
  expect_rejected(validate(s), "initial_depth[3]", "[0, inf)");
  s = valid_reach();
  s.initial_discharge.assign(10, 0.0);
  s.initial_discharge[7] = std::numeric_limits<double>::infinity();
  expect_rejected(validate(s), "initial_discharge[7]", "finite");
  s = valid_reach();
  s.bed_elevation.assign(10, 0.0);
  s.bed_elevation[0] = std::nan("");
  expect_rejected(validate(s), "bed_elevation[0]", "finite");
}

TEST(ReachSpec, NegativeInitialDepthIsRejected) {
  ReachSpec s = valid_reach();
  s.initial_depth[2] = -0.01;
  expect_rejected(validate(s), "initial_depth[2]", "[0, inf)");
}

TEST(ReachSpec, PerCellArrayOfTheWrongLengthIsRejected) {
  ReachSpec s = valid_reach();
  s.bed_elevation.assign(9, 0.0);
  EXPECT_NE(validate(s).message().find("bed_elevation has 9 values; expected 10"), std::string::npos);
}

TEST(Canal, InvalidOptionsRefuseReachesAndSteps) {
  SolverOptions o;
  o.cfl = 2.0;
  Canal canal(o);
  EXPECT_FALSE(canal.options_status());
  expect_rejected(canal.add_reach(valid_reach()), "SolverOptions::cfl", "(0, 1]");
  EXPECT_FALSE(canal.step());
}

TEST(Canal, InvalidReachIsRejectedByAddReach) {
  Canal canal;
  ReachSpec s = valid_reach();
  s.section.bottom_width = -1.0;
  expect_rejected(canal.add_reach(s), "bottom_width", "[0, inf)");
  EXPECT_EQ(canal.reach_count(), 0);
}

}  // namespace
}  // namespace canalsim::solver
