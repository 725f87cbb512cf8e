// Parameter statistics (calibration/statistics.hpp) on a problem solved by hand: one level offset
// fitted to N residuals that alternate ±σ (no autocorrelation to correct for), J = 1 per sample,
// so the std is the mean's, σ sqrt(N / (N − 1)) / sqrt(N) = σ / sqrt(N − 1).
#include "calibration/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "calibration/parameters.hpp"
#include "scenarios/builtin.hpp"

namespace canalsim::calibration {
namespace {

constexpr std::size_t kSamples = 101;

// The offset of y_dwe at `value` mm, with residuals ±sigma mm about it.
ParameterStatistics offset_statistics(double value, double sigma) {
  const std::vector<Parameter> p = select_parameters(scenarios::builtin_scenario("lab"), {"offset_y_dwe_mm"});
  std::vector<double> r(kSamples);
  for (std::size_t k = 0; k < kSamples; ++k) r[k] = k % 2 == 0 ? sigma : -sigma;
  const std::vector<double> J(kSamples, 1.0);
  return parameter_statistics(p, {p[0].to_search(value)}, J, r, {r});
}

double expected_std(double sigma) {
  const double n = static_cast<double>(kSamples);
  return sigma * std::sqrt(n / (n - 1.0)) / std::sqrt(n);  // s = sqrt(rᵀr / (N − p)), std = s / sqrt(N)
}

// An offset near zero on clean recordings is determined far below the sensor's resolution: a std
// of 4e-4 mm is not "relative std 400 %" of a value of 1e-4 mm.
TEST(ParameterStatistics, AnOffsetNearZeroDeterminedFinelyIsIdentifiable) {
  const double sigma = 4e-4 * std::sqrt(static_cast<double>(kSamples - 1));
  const ParameterStatistics s = offset_statistics(1e-4, sigma);
  EXPECT_NEAR(s.std[0], expected_std(sigma), 1e-3 * expected_std(sigma));
  EXPECT_NEAR(s.std[0], 4e-4, 1e-6);
  EXPECT_TRUE(s.unidentified.empty()) << s.unidentified.front().reason;
}

// An offset the recordings leave open by more than half of ten steps (0.25 mm) is named, whatever
// its value — also exactly zero.
TEST(ParameterStatistics, AnOffsetLeftOpenIsNamedEvenAtZero) {
  for (const double value : {0.0, 0.1}) {
    const double sigma = 0.4 * std::sqrt(static_cast<double>(kSamples - 1));
    const ParameterStatistics s = offset_statistics(value, sigma);
    EXPECT_NEAR(s.std[0], 0.4, 1e-3);
    ASSERT_EQ(s.unidentified.size(), 1u) << value;
    EXPECT_EQ(s.unidentified.front().parameters, std::vector<std::string>{"offset_y_dwe_mm"});
    EXPECT_NE(s.unidentified.front().reason.find("relative std 80 %"), std::string::npos) << s.unidentified.front().reason;
  }
  // Below half of ten steps it is determined.
  const ParameterStatistics fine = offset_statistics(0.0, 0.2 * std::sqrt(static_cast<double>(kSamples - 1)));
  EXPECT_TRUE(fine.unidentified.empty());
}

}  // namespace
}  // namespace canalsim::calibration
