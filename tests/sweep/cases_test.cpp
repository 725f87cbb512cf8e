// The cases of a sweep file: the grid keys' Cartesian product in the file's order, listed and
// ranged grids, log spacing, and draws that depend only on the seed and the point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <set>

#include "sweep/cases.hpp"
#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {
namespace {

SweepFile parse(const std::string& text) { return parse_sweep_file(text, "cases.toml", "."); }

TEST(SweepCases, GridKeysCombineAsACartesianProductTheLastKeyFastest) {
  const SweepFile f = parse(R"(
scenario = "lab"
experiments = ["op1", "op2"]
[[vary]]
key = "pools[1].length_m"
values = [4.0, 5.0, 6.0]
[[vary]]
key = "pools[1].manning_n"
values = [0.010, 0.012]
)");
  ASSERT_EQ(case_count(f), 3u * 2u * 2u);
  EXPECT_EQ(grid_point_count(f), 6u);
  std::set<std::pair<double, double>> points;
  for (std::size_t i = 0; i < case_count(f); ++i) {
    const Case c = case_at(f, i);
    EXPECT_EQ(c.index, i);
    EXPECT_EQ(c.experiment, i % 2) << "each point runs every experiment in turn";
    EXPECT_EQ(c.point, i / 2);
    points.insert({c.values[0], c.values[1]});
  }
  EXPECT_EQ(points.size(), 6u) << "every combination once";
  EXPECT_EQ(case_at(f, 0).values, (std::vector<double>{4.0, 0.010}));
  EXPECT_EQ(case_at(f, 2).values, (std::vector<double>{4.0, 0.012}));
  EXPECT_EQ(case_at(f, 4).values, (std::vector<double>{5.0, 0.010}));
  EXPECT_EQ(case_at(f, 11).values, (std::vector<double>{6.0, 0.012}));
  EXPECT_EQ(f.experiments[case_at(f, 3).experiment], "op2");
}

TEST(SweepCases, RangesSpaceEvenlyOrInTheLogarithmWithExactEnds) {
  const SweepFile f = parse(R"(
scenario = "lab"
experiments = ["op1"]
[[vary]]
key = "pools[1].length_m"
from = 4.0
to = 6.0
count = 5
[[vary]]
key = "pools[1].manning_n"
from = 0.001
to = 0.1
count = 3
spacing = "log"
)");
  ASSERT_EQ(f.vary[0].grid.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) EXPECT_DOUBLE_EQ(f.vary[0].grid[k], 4.0 + 0.5 * static_cast<double>(k));
  EXPECT_EQ(f.vary[0].grid.back(), 6.0);
  ASSERT_EQ(f.vary[1].grid.size(), 3u);
  EXPECT_EQ(f.vary[1].grid.front(), 0.001);
  EXPECT_NEAR(f.vary[1].grid[1], 0.01, 1e-15);
  EXPECT_EQ(f.vary[1].grid.back(), 0.1);
  EXPECT_TRUE(f.vary[1].logarithmic);
  EXPECT_FALSE(f.vary[0].logarithmic);
  EXPECT_EQ(case_count(f), 15u);
}

const char* kDrawn = R"(
scenario = "lab"
experiments = ["op1", "op2"]
seed = 7
draws = 50
[[vary]]
key = "pools[1].length_m"
values = [4.0, 5.0]
[[vary]]
key = "pools[1].manning_n"
distribution = "uniform"
low = 0.009
high = 0.012
[[vary]]
key = "pools[1].bed_slope"
distribution = "normal"
mean = 0.001
std = 0.0002
[[vary]]
key = "head_gate.discharge_coefficient"
distribution = "lognormal"
median = 1.0
sigma = 0.05
)";

TEST(SweepCases, DrawsAreReproducibleIndependentOfOrderAndSharedByAPointsExperiments) {
  const SweepFile f = parse(kDrawn);
  ASSERT_EQ(case_count(f), 2u * 50u * 2u);
  std::vector<Case> forward;
  for (std::size_t i = 0; i < case_count(f); ++i) forward.push_back(case_at(f, i));
  // The same cases asked for backwards, and from another parse of the same file.
  const SweepFile again = parse(kDrawn);
  for (std::size_t i = case_count(f); i-- > 0;) EXPECT_EQ(case_at(again, i).values, forward[i].values) << i;
  std::set<double> manning;
  double sum_slope = 0.0;
  for (const Case& c : forward) {
    EXPECT_EQ(c.values, forward[c.point * 2].values) << "a point's experiments share its draw";
    EXPECT_EQ(c.values[0], c.point < 50 ? 4.0 : 5.0) << "draws vary fastest within a grid point";
    EXPECT_GE(c.values[1], 0.009);
    EXPECT_LT(c.values[1], 0.012);
    EXPECT_GT(c.values[3], 0.0);
    manning.insert(c.values[1]);
    sum_slope += c.values[2];
  }
  EXPECT_EQ(manning.size(), 100u) << "every point draws anew";
  EXPECT_NEAR(sum_slope / 200.0, 0.001, 0.0001);
  // Another seed, other draws; the grid keys unchanged.
  std::string reseeded = kDrawn;
  reseeded.replace(reseeded.find("seed = 7"), 8, "seed = 8");
  const SweepFile other = parse(reseeded);
  EXPECT_NE(case_at(other, 0).values[1], forward[0].values[1]);
  EXPECT_EQ(case_at(other, 0).values[0], forward[0].values[0]);
}

TEST(SweepCases, ACasesScenarioHoldsItsValuesExactlyAndTheExperimentsOwnKeys) {
  const SweepFile f = parse(R"(
scenario = "lab"
experiments = ["op1", "op2"]
duration_s = 20
seed = 3
[[vary]]
key = "pools[1].manning_n"
distribution = "uniform"
low = 0.009
high = 0.012
[[vary]]
key = "experiment.operating_opening_mm"
values = [18.5]
)");
  const Case c = case_at(f, 1);  // point 0, op2
  const scenarios::Scenario s = case_scenario(f, c);
  EXPECT_EQ(s.pools.front().manning_n, c.values[0]) << "the text written carries the drawn double exactly";
  const auto* op2 = s.find_experiment("op2");
  const auto* op1 = s.find_experiment("op1");
  EXPECT_EQ(op2->operating_opening_mm, 18.5);
  EXPECT_EQ(op1->operating_opening_mm, 15.0) << "only the case's experiment is edited";
  EXPECT_EQ(op2->duration_s, 20.0);
}

TEST(SweepCases, NumbersAreWrittenExactlyAndShortly) {
  EXPECT_EQ(exact_number(0.009), "0.009");
  EXPECT_EQ(exact_number(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(exact_number(1000000.0), "1000000") << "an integer key (cells) takes it";
  EXPECT_EQ(exact_number(-4.0), "-4");
  EXPECT_EQ(exact_number(1e20), "1e+20");
  double x = 1.0 / 3.0;
  for (int k = 0; k < 200; ++k, x = x * 1.37 + 1e-3 / (k + 1.0)) {
    EXPECT_EQ(std::strtod(exact_number(x).c_str(), nullptr), x) << exact_number(x);
    EXPECT_EQ(std::strtod(exact_number(-x * 1e-7).c_str(), nullptr), -x * 1e-7);
  }
}

}  // namespace
}  // namespace canalsim::sweep
