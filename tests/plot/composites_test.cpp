// The composite figures: the autocorrelation of white and AR(1) noise against its band ±1.96/√n,
// the residual panel under a fit, the zoom on a command change and the Bode plot's axes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "testing/signals.hpp"

#include "plot/composites.hpp"
#include "plot/palette.hpp"
#include "testing/svg_checks.hpp"

namespace {

using namespace canalsim::plot;
using namespace canalsim::plot_test;

std::vector<double> ar1(double phi, std::size_t n, unsigned seed) { return canalsim::testing::ar1_noise(phi, n, seed); }

TEST(Autocorrelation, WhiteNoiseStaysInsideTheBandAndTheBandIs1_96OverRootN) {
  const std::size_t n = 4000;
  const Autocorrelation a = residual_autocorrelation(ar1(0.0, n, 7), 40);
  EXPECT_DOUBLE_EQ(a.bound, 1.96 / std::sqrt(4000.0));
  EXPECT_EQ(a.samples, n);
  ASSERT_EQ(a.lags.size(), 40u);
  EXPECT_EQ(a.lags.front(), 1.0);
  int outside = 0;
  for (const double r : a.values) outside += std::abs(r) > a.bound ? 1 : 0;
  EXPECT_LE(outside, 6);  // 5 % of 40 expected; 6 or more happens with probability < 0.05
}

TEST(Autocorrelation, AR1NoiseDecaysAsPhiToTheLag) {
  const double phi = 0.8;
  const Autocorrelation a = residual_autocorrelation(ar1(phi, 20000, 11), 5);
  // r(k) = φ^k for AR(1); the sampling error of r(k) is about √((1+φ²)/(1−φ²)/n) ≈ 0.02.
  for (std::size_t k = 0; k < a.values.size(); ++k) {
    EXPECT_NEAR(a.values[k], std::pow(phi, static_cast<double>(k + 1)), 0.05) << "lag " << k + 1;
  }
  EXPECT_GT(a.values[0], 10.0 * a.bound);
}

TEST(Autocorrelation, TheFigureShadesTheBandAndLeavesNonFiniteSamplesOut) {
  std::vector<double> e = ar1(0.0, 400, 3);
  e[10] = std::nan("");
  const Figure f = autocorrelation_figure("acf", "autocorrelation", {{"nominal", e, ""}, {"calibrated", e, ""}}, 20);
  ASSERT_EQ(f.panels.size(), 2u);
  const Series& band = f.panels[0].series[0];
  EXPECT_EQ(band.style, Style::band);
  EXPECT_DOUBLE_EQ(band.y_upper[0], 1.96 / std::sqrt(399.0));
  EXPECT_DOUBLE_EQ(band.y[0], -1.96 / std::sqrt(399.0));
  EXPECT_EQ(f.panels[0].series[1].style, Style::stems);
  EXPECT_EQ(f.panels[0].series[1].colour, series_colour("nominal"));
  EXPECT_EQ(f.panels[1].series[1].colour, series_colour("calibrated"));
  EXPECT_EQ(unbalanced_tags(render_svg(f)), "");
}

Comparison step_response() {
  Comparison c;
  c.name = "op1_levels_and_residual";
  std::vector<double> u;
  for (int k = 0; k < 1000; ++k) {
    const double t = 0.5 * k;
    c.t.push_back(t);
    u.push_back(t < 200.0 ? 100.0 : 120.0);
    c.measured.y.push_back(t < 200.0 ? 300.0 : 300.0 + 10.0 * (1.0 - std::exp(-(t - 200.0) / 20.0)));
  }
  c.measured.name = "recorded";
  c.models.push_back({"nominal", c.measured.y, "nominal model"});
  c.models.push_back({"calibrated", c.measured.y, "calibrated"});
  c.models[0].y[5] += 3.0;
  return c;
}

TEST(MeasuredVsModel, TheResidualPanelIsInMillimetresBelowTheLevels) {
  const Comparison c = step_response();
  const Figure f = measured_vs_model(c);
  ASSERT_EQ(f.panels.size(), 2u);
  EXPECT_EQ(f.panels[1].y.title(), "residual [mm]");
  EXPECT_TRUE(f.panels[1].y.symmetric);
  const std::vector<Curve> r = residuals(c);
  EXPECT_DOUBLE_EQ(r[0].y[5], -3.0);  // measured − model
  EXPECT_DOUBLE_EQ(r[1].y[5], 0.0);
  const std::vector<PanelFrame> frames = layout(f);
  // max |r| = 3 → ±3; a step of 6 / 4 = 1.5 → 2 widens it to ±4.
  EXPECT_DOUBLE_EQ(frames[1].y.low, -4.0);
  EXPECT_DOUBLE_EQ(frames[1].y.high, 4.0);
  EXPECT_GT(frames[1].top, frames[0].top + frames[0].height);
  // Each model has its colour in both panels.
  EXPECT_EQ(f.panels[0].series[1].colour, f.panels[1].series[0].colour);
}

TEST(StepZoom, AWindowAroundTheLargestCommandChange) {
  const Comparison c = step_response();
  std::vector<double> u(c.t.size());
  for (std::size_t k = 0; k < u.size(); ++k) u[k] = c.t[k] < 200.0 ? 100.0 : 120.0;
  EXPECT_EQ(largest_command_change(c.t, u), 200.0);
  const auto zoom = step_zoom(c, u, "mm");
  ASSERT_TRUE(zoom.has_value());
  const std::vector<double>& t = zoom->panels[0].series[0].x;
  // A twelfth of 499.5 s (41.6 s), a fifth of it before the change.
  EXPECT_NEAR(t.front(), 200.0 - 0.2 * 499.5 / 12.0, 0.5);
  EXPECT_NEAR(t.back(), 200.0 + 0.8 * 499.5 / 12.0, 0.5);
  EXPECT_EQ(zoom->panels[1].series[0].style, Style::step);
  EXPECT_EQ(zoom->panels[0].markers.front().x, 200.0);
  EXPECT_FALSE(step_zoom(c, std::vector<double>(c.t.size(), 100.0), "mm").has_value());
}

TEST(Bode, GainInDecibelsAbovePhaseInDegreesOnDecades) {
  std::vector<double> omega, gain, phase;
  for (int k = 0; k <= 60; ++k) {
    const double w = std::pow(10.0, -2.0 + 3.0 * k / 60.0);
    omega.push_back(w);
    gain.push_back(-10.0 * std::log10(1.0 + w * w));
    phase.push_back(-std::atan(w) * 180.0 / M_PI - w * 180.0);  // a lag and a delay of π s
  }
  const Figure f = bode_figure("bode_op1", "Bode", omega, {{"LFOM", gain, phase, ""}}, Window{0.1, 2.0});
  const std::vector<PanelFrame> frames = layout(f);
  EXPECT_EQ(frames[0].x.ticks, (std::vector<double>{0.01, 0.1, 1.0, 10.0}));
  EXPECT_EQ(f.panels[0].y.title(), "gain [dB]");
  EXPECT_EQ(f.panels[1].y.title(), "phase [deg]");
  EXPECT_EQ(f.panels[0].series[0].colour, series_colour("LFOM"));
  const std::string svg = render_svg(f);
  EXPECT_EQ(unbalanced_tags(svg), "");
  for (const auto& text : text_nodes(svg)) EXPECT_FALSE(is_negative_zero(text)) << text;
  // The phase axis (down to about −1800 degrees) reads in steps like −500, never −1.78e+03.
  EXPECT_EQ(svg.find("e+03"), std::string::npos);
  EXPECT_NE(svg.find(">-1000<"), std::string::npos);
}

TEST(Palette, TheSameModelHasTheSameColourEverywhere) {
  EXPECT_EQ(series_colour("LFOM"), series_colour("lfom", 5));
  EXPECT_NE(series_colour("LIOM"), series_colour("LFOM"));
  EXPECT_NE(series_colour("NLIOM-S"), series_colour("NLFOM-S"));
  EXPECT_NE(series_colour("NLIOM-F"), series_colour("NLFOM-F"));
  EXPECT_NE(series_colour("nominal"), series_colour("calibrated"));
  EXPECT_NE(series_colour("recorded"), series_colour("corrected"));
  EXPECT_EQ(named_colour("op1"), "");
  EXPECT_NE(series_colour("op1", 0), series_colour("op2", 1));
}

}  // namespace
