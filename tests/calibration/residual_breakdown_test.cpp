// The residual breakdown (calibration/residual_breakdown.hpp) on series whose residual is built
// from parts placed by hand — an offset in the top third of the level, a transient after each
// command switch, white alternation — so each group's RMS, mean and each choice's share follow in
// closed form.
#include "calibration/residual_breakdown.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "calibration/calibrate.hpp"

namespace canalsim::calibration {
namespace {

constexpr double kPeriod = 0.13;

const BreakdownGroup& group(const ResidualBreakdown& b, const std::string& axis, const std::string& name) {
  for (const BreakdownGroup& g : b.groups) {
    if (g.axis == axis && g.name == name) return g;
  }
  ADD_FAILURE() << axis << " / " << name << " missing";
  static const BreakdownGroup none;
  return none;
}

// A recording of 300 s: the level a sine of period 100 s about 50 mm, the command switching every
// 20 s. Residual parts: `offset` where the level is in its top third, `transient` in the 2 s after
// each switch, ±`alternation` alternating sample by sample.
Series series(const std::string& name, double offset, double transient, double alternation) {
  Series s;
  s.recording = name;
  s.channel = "y_dwe_mm";
  const std::size_t n = static_cast<std::size_t>(300.0 / kPeriod);
  double switched = -1.0e9;  // the first sample of each new command
  for (std::size_t k = 0; k < n; ++k) {
    const double t = kPeriod * static_cast<double>(k);
    const double level = 50.0 + 5.0 * std::sin(2.0 * std::numbers::pi * t / 100.0);
    if (k > 0 && std::floor(t / 20.0) != s.u.back()) switched = t;
    const double since = t - switched;
    const bool top = level > 50.0 + 5.0 * std::sin(std::numbers::pi / 6.0);  // above the upper third of a sine's time
    double r = (k % 2 == 0 ? alternation : -alternation);
    if (top) r += offset;
    if (since < 2.0) r += transient;
    s.t.push_back(t);
    s.u.push_back(std::floor(t / 20.0));
    s.recorded.push_back(level);
    s.calibrated.push_back(level - r);
    s.nominal.push_back(level);
  }
  return s;
}

TEST(ResidualBreakdown, AStaticErrorAtHighLevelsSitsInTheTopThirdAndInTheSlowBand) {
  const std::vector<Series> model = {series("op1", 0.2, 0.0, 0.05)};
  const std::vector<Series> rating = {series("op1", 0.0, 0.0, 0.05)};  // a choice that removes the offset
  const ResidualBreakdown b = residual_breakdown(model, {{"rating", &rating}});
  ASSERT_EQ(b.choices, std::vector<std::string>{"rating"});
  // A sine spends a third of its time above sin(π/6) of its amplitude: that third is the top one.
  const BreakdownGroup& high = group(b, "level", "high third");
  EXPECT_NEAR(high.mean_mm, 0.2, 0.002);
  EXPECT_NEAR(high.rms_mm, std::sqrt(0.2 * 0.2 + 0.05 * 0.05), 0.002);
  EXPECT_NEAR(high.removed.at(0), 0.2 * 0.2 / (0.2 * 0.2 + 0.05 * 0.05), 0.01);
  const BreakdownGroup& low = group(b, "level", "low third");
  EXPECT_NEAR(low.mean_mm, 0.0, 1e-3);
  EXPECT_NEAR(low.rms_mm, 0.05, 1e-3);
  EXPECT_NEAR(low.removed.at(0), 0.0, 1e-9);
  // The offset comes in 33 s blocks: mostly slower than 20 s; the alternation is all fast.
  const BreakdownGroup& slow = group(b, "frequency", "slow (> 20 s)");
  const BreakdownGroup& fast = group(b, "frequency", "fast (< 2 s)");
  EXPECT_GT(slow.removed.at(0), 0.95);
  EXPECT_NEAR(fast.rms_mm, 0.05, 0.01);
  EXPECT_LT(std::abs(fast.removed.at(0)), 0.1);
  // The whole recording: one operating point, every sample.
  const BreakdownGroup& op = group(b, "operating point", "op1");
  EXPECT_EQ(op.samples, model.front().t.size());
}

// The model's regime marks where the offset lives: submerged at the top of the level (as a
// rising tailwater drowns the gate), free elsewhere. Without a regime there is no regime axis.
TEST(ResidualBreakdown, TheRegimeAxisFollowsTheModelsRegimeAtEachSample) {
  Series s = series("op1", 0.2, 0.0, 0.0);
  for (std::size_t k = 0; k < s.t.size(); ++k) s.regime.push_back(s.recorded[k] - s.calibrated[k] > 0.1 ? 1.0 : 0.0);
  const ResidualBreakdown b = residual_breakdown({s});
  EXPECT_NEAR(group(b, "regime", "submerged").mean_mm, 0.2, 1e-12);
  EXPECT_NEAR(group(b, "regime", "free").rms_mm, 0.0, 1e-12);
  EXPECT_EQ(group(b, "regime", "submerged").samples + group(b, "regime", "free").samples, s.t.size());
  // In the axes' order: after the operating points.
  EXPECT_EQ(b.groups.at(1).axis, "regime");
  const ResidualBreakdown without = residual_breakdown({series("op1", 0.2, 0.0, 0.0)});
  for (const BreakdownGroup& g : without.groups) EXPECT_NE(g.axis, "regime");
}

TEST(ResidualBreakdown, ATransientAfterEachSwitchSitsInTheSoonestThird) {
  const std::vector<Series> model = {series("op2", 0.0, 0.3, 0.05)};
  const std::vector<Series> dynamics = {series("op2", 0.0, 0.0, 0.05)};
  const ResidualBreakdown b = residual_breakdown(model, {{"dynamics", &dynamics}});
  std::vector<BreakdownGroup> after;
  for (const BreakdownGroup& g : b.groups) {
    if (g.axis == "after a switch") after.push_back(g);
  }
  ASSERT_EQ(after.size(), 3u);
  // 14 switches 20 s apart and 20 s before the first: a third of the 300 s lies within
  // 300 / 3 / 14 = 7.14 s of a switch, the next within 14.3 s.
  EXPECT_EQ(after[0].name, "< 7 s");  // to two digits: the sample nearest 7.14 s
  EXPECT_EQ(after[1].name, "7 s to 14 s");
  // The 2 s transient is 2 / 7.14 of the soonest third.
  const double share = 2.0 / 7.14;
  EXPECT_NEAR(after[0].mean_mm, 0.3 * share, 0.01);
  EXPECT_NEAR(after[0].removed.at(0), 0.09 * share / (0.09 * share + 0.0025), 0.02);
  for (int i : {1, 2}) {
    EXPECT_NEAR(after[i].rms_mm, 0.05, 1e-3) << after[i].name;
    EXPECT_NEAR(after[i].removed.at(0), 0.0, 1e-9) << after[i].name;
  }
}

TEST(ResidualBreakdown, OtherChannelsAreLeftOutAndAMismatchedChoiceHasNoShare) {
  Series discharge = series("op1", 0.0, 0.0, 1.0);
  discharge.channel = "q_lps";
  Series validation = series("op3b", 0.1, 0.0, 0.0);
  validation.validation = true;
  const std::vector<Series> model = {series("op1", 0.0, 0.0, 0.05), discharge, validation};
  const std::vector<Series> shorter = {Series{"op1", "y_dwe_mm", false, {0.0}, {1.0}, {1.0}, {1.0}, {0.0}, {}}};
  const ResidualBreakdown b = residual_breakdown(model, {{"other", &shorter}});
  EXPECT_NEAR(group(b, "operating point", "op1").rms_mm, 0.05, 1e-9);  // not the discharge's 1 l/s
  EXPECT_EQ(group(b, "operating point", "op3b (validation)").samples, validation.t.size());
  for (const BreakdownGroup& g : b.groups) EXPECT_TRUE(std::isnan(g.removed.at(0))) << g.name;
  // Axes in order: operating points, level, after a switch, frequency.
  ASSERT_FALSE(b.groups.empty());
  EXPECT_EQ(b.groups.front().axis, "operating point");
  EXPECT_EQ(b.groups.back().axis, "frequency");
}

}  // namespace
}  // namespace canalsim::calibration
