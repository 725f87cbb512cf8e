// Tests of reduced_models/metrics.*: Nrmse (eq. 19), IAE (eq. 20), IAE_c (eq. 21), Δp (eq. 22).
#include "reduced_models/metrics.hpp"
#include "testing/synthetic.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace canalsim::reduced {
namespace {

TEST(Nrmse, IsOneHundredForAPerfectFitAndZeroForTheMean) {
  const std::vector<double> y{1.0, 3.0, 2.0, 6.0};
  EXPECT_DOUBLE_EQ(nrmse_percent(y, y), 100.0);
  const std::vector<double> mean(4, 3.0);
  EXPECT_NEAR(nrmse_percent(mean, y), 0.0, 1e-12);
}

TEST(Nrmse, IsOneMinusTheRatioOfErrorNormToDeviationNormInPercent) {
  const std::vector<double> y{0.0, 2.0, 4.0};        // mean 2, ‖y − mean‖ = √8
  const std::vector<double> m{0.0, 2.0, 3.0};        // ‖m − y‖ = 1
  EXPECT_NEAR(nrmse_percent(m, y), 100.0 * (1.0 - 1.0 / std::sqrt(8.0)), 1e-12);
}

TEST(Nrmse, CanBeNegativeForAModelWorseThanTheMean) {
  const std::vector<double> y{0.0, 1.0};
  const std::vector<double> m{5.0, -5.0};
  EXPECT_LT(nrmse_percent(m, y), 0.0);
}

TEST(Iae, IsTheRectangleRuleIntegralOfTheAbsoluteError) {
  const std::vector<double> y{0.0, 1.0, 2.0};
  const std::vector<double> m{1.0, 1.0, 0.0};
  EXPECT_DOUBLE_EQ(iae(m, y, 0.5), 0.5 * (1.0 + 0.0 + 2.0));
  EXPECT_DOUBLE_EQ(iae_combined({m, m}, {y, y}, {0.5, 1.0}), 1.5 + 3.0);
}

TEST(Metrics, RejectSeriesOfDifferentLengths) {
  EXPECT_THROW(iae({1.0}, {1.0, 2.0}, 0.1), std::invalid_argument);
  EXPECT_THROW(nrmse_percent({}, {}), std::invalid_argument);
}

TEST(UncertaintyIndex, IsTheLargestRelativeDeviationFromTheNominalParameter) {
  // Table 1 of the paper: K_j = 0.6806, 0.4546, 0.5576, 0.589; nominal 0.5546 → 22.7 %
  // (the paper prints 16.6 %, which matches neither this nor any single op; the formula is eq. 22).
  EXPECT_NEAR(uncertainty_index({0.6806, 0.4546, 0.5576, 0.589}, 0.5546),
              (0.6806 - 0.5546) / 0.5546, 1e-12);
  EXPECT_DOUBLE_EQ(uncertainty_index({4.9, 4.9}, 4.9), 0.0);
}

TEST(UncertaintyIndex, IsComputedForEveryParameterOfTheModel) {
  Model a{ModelKind::lfom, {}, {}}, b = a, nominal = a;
  a.p.K = 1.1;
  b.p.K = 0.9;
  nominal.p.K = 1.0;
  a.p.lambda = 0.6;
  b.p.lambda = 0.5;
  nominal.p.lambda = 0.5;
  const auto dp = uncertainty_indices({a, b}, nominal);
  EXPECT_NEAR(dp.at("K"), 0.1, 1e-12);
  EXPECT_NEAR(dp.at("lambda"), 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(dp.at("L"), 0.0);
  EXPECT_EQ(dp.count("gamma"), 0u);
}

}  // namespace
}  // namespace canalsim::reduced
