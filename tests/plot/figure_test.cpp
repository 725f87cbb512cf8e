// The figure builder: a data point lands on the pixel worked out by hand, log axes put decades
// where they belong, a flat residual gets a calm symmetric axis, and the SVG is well formed with no
// nan, inf or -0 in its text whatever the data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "plot/figure.hpp"
#include "testing/svg_checks.hpp"

namespace {

using namespace canalsim::plot;
using namespace canalsim::plot_test;

Figure one_panel(Axis x, Axis y, std::vector<double> xs, std::vector<double> ys, Style style = Style::scatter) {
  Figure f;
  f.name = "test";
  Panel p;
  p.x = std::move(x);
  p.y = std::move(y);
  Series s;
  s.colour = "#000000";
  s.style = style;
  s.x = std::move(xs);
  s.y = std::move(ys);
  p.series.push_back(std::move(s));
  f.panels.push_back(std::move(p));
  return f;
}

Axis fixed(double low, double high, const std::string& unit = "") {
  Axis a{"value", unit};
  a.low = low;
  a.high = high;
  return a;
}

TEST(Figure, APointLandsOnThePixelWorkedOutByHand) {
  // x in [0, 10], y in [0, 100] (ticks 0, 20, …, 100); no title, no legend, no panel title.
  const Figure f = one_panel(fixed(0, 10), fixed(0, 100), {5.0}, {25.0});
  const std::vector<PanelFrame> frames = layout(f);
  ASSERT_EQ(frames.size(), 1u);
  const PanelFrame& fr = frames[0];
  // Left: the side (10) + the widest y label "100" (3 × 6.6) + 10 + the y title's 12 + 10 = 61.8.
  EXPECT_NEAR(fr.left, 61.8, 1e-9);
  // Width: 960 − 2 × 10 − 51.8 − 16 (right margin) = 872.2; top: 6 (no title) + 6 (no panel titles).
  EXPECT_NEAR(fr.width, 872.2, 1e-9);
  EXPECT_NEAR(fr.top, 12.0, 1e-9);
  EXPECT_NEAR(fr.height, 200.0, 1e-9);
  // (5, 25): halfway across, a quarter up from the bottom.
  EXPECT_NEAR(fr.pixel_x(5.0), 61.8 + 436.1, 1e-9);
  EXPECT_NEAR(fr.pixel_y(25.0), 12.0 + 150.0, 1e-9);
  EXPECT_NE(render_svg(f).find("<circle cx='497.9' cy='162.0'"), std::string::npos);
}

TEST(Figure, ALogAxisPutsEachDecadeAnEqualWidthApart) {
  Axis x{"ω", "rad/s"};
  x.scale = Scale::log;
  const Figure f = one_panel(x, fixed(0, 1), {0.03, 10.0, 200.0}, {0.5, 0.5, 0.5});
  const PanelFrame fr = layout(f)[0];
  // The data's decades extended outwards: [0.01, 1000], five decades.
  EXPECT_DOUBLE_EQ(fr.x.low, 0.01);
  EXPECT_DOUBLE_EQ(fr.x.high, 1000.0);
  EXPECT_EQ(fr.x.ticks, (std::vector<double>{0.01, 0.1, 1.0, 10.0, 100.0, 1000.0}));
  EXPECT_EQ(fr.x.minor_ticks.size(), 5u * 8u);
  EXPECT_NEAR(fr.pixel_x(10.0) - fr.left, 0.6 * fr.width, 1e-9);
  EXPECT_NEAR(fr.pixel_x(0.1) - fr.pixel_x(0.01), fr.width / 5.0, 1e-9);
  const std::string svg = render_svg(f);
  for (const char* label : {">0.01<", ">0.1<", ">1<", ">10<", ">100<", ">1000<", ">ω [rad/s]<"}) {
    EXPECT_NE(svg.find(label), std::string::npos) << label;
  }
}

TEST(Figure, AFlatResidualGetsACalmSymmetricAxis) {
  Axis residual{"residual", "mm"};
  residual.symmetric = true;
  residual.min_half_span = 0.5;
  residual.ticks = 4;
  for (const double size : {0.0, 1e-12, 0.02}) {
    std::vector<double> t, r;
    for (int k = 0; k < 100; ++k) {
      t.push_back(k);
      r.push_back(size * std::sin(k));
    }
    const Figure f = one_panel(Axis{"t", "s"}, residual, t, r, Style::line);
    const PanelFrame fr = layout(f)[0];
    EXPECT_DOUBLE_EQ(fr.y.low, -0.5) << size;
    EXPECT_DOUBLE_EQ(fr.y.high, 0.5) << size;
    EXPECT_EQ(fr.y.ticks, (std::vector<double>{-0.5, 0.0, 0.5})) << size;
    const std::string svg = render_svg(f);
    for (const auto& text : text_nodes(svg)) EXPECT_FALSE(is_negative_zero(text)) << text;
    EXPECT_NE(svg.find(">residual [mm]<"), std::string::npos);
  }
}

TEST(Figure, ALargerResidualGetsItsOwnSymmetricRange) {
  Axis residual{"residual", "mm"};
  residual.symmetric = true;
  residual.min_half_span = 0.5;
  residual.ticks = 4;
  const PanelFrame fr = layout(one_panel(Axis{"t", "s"}, residual, {0, 1, 2}, {-0.3, 2.7, 1.0}, Style::line))[0];
  // max |r| = 2.7 → ±2.7, step of 5.4 / 4 = 1.35 → 2, widened to ±4.
  EXPECT_DOUBLE_EQ(fr.y.low, -4.0);
  EXPECT_DOUBLE_EQ(fr.y.high, 4.0);
  EXPECT_EQ(fr.y.ticks, (std::vector<double>{-4, -2, 0, 2, 4}));
}

TEST(Figure, TheSvgIsWellFormedWithoutNanInfOrMinusZeroWhateverTheData) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  Figure f;
  f.name = "odd data";
  f.title = "Odd data & <tags>";
  f.columns = 2;
  f.share_x = true;
  const std::vector<std::vector<double>> ys = {
      {nan, nan, nan}, {inf, -inf, 1.0}, {0.0, 0.0, 0.0}, {-1e-300, 1e-300, 0.0}, {1e12, -1e12, 3.0}, {}};
  for (std::size_t i = 0; i < ys.size(); ++i) {
    Panel p;
    p.title = "panel " + std::to_string(i);
    p.x = Axis{"t", "s"};
    p.y = Axis{"y", "mm"};
    if (i == 3) p.y.scale = Scale::log;  // nothing positive enough to matter, zeros, negatives
    for (const Style style : {Style::line, Style::step, Style::scatter, Style::stems}) {
      Series s;
      s.label = "series";
      s.colour = "#123456";
      s.style = style;
      s.x = {-1.0, 0.0, 1.0};
      s.y = ys[i];
      s.marks = {0, 2, 7};
      p.series.push_back(s);
    }
    Series band;
    band.style = Style::band;
    band.colour = "#abcdef";
    band.x = {0.0, 1.0};
    band.y = {nan, -1.0};
    band.y_upper = {inf, 1.0};
    p.series.push_back(band);
    p.windows = {{0.2, 0.4}};
    p.window_label = "window";
    p.markers = {{0.5, "marker"}, {nan, "lost"}};
    f.panels.push_back(std::move(p));
  }
  const std::string svg = svg_document(f);
  EXPECT_EQ(unbalanced_tags(svg), "");
  std::string lower = svg;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  EXPECT_EQ(lower.find("nan"), std::string::npos);
  EXPECT_EQ(lower.find("inf"), std::string::npos);
  for (const auto& text : text_nodes(svg)) EXPECT_FALSE(is_negative_zero(text)) << text;
  EXPECT_NE(svg.find("Odd data &amp; &lt;tags&gt;"), std::string::npos);
  EXPECT_NE(svg.find("id='odd_data-clip0'"), std::string::npos);  // ids from the name, made safe
}

TEST(Figure, OneLegendForTheFigureWithEachSeriesOnce) {
  Figure f;
  f.name = "legend";
  f.columns = 2;
  for (int i = 0; i < 2; ++i) {
    Panel p;
    p.x = Axis{"t", "s"};
    p.y = Axis{"level", "mm"};
    p.series.push_back(Series{"recorded", "#222222", Style::line, {0, 1}, {0, 1}, {}, false, 1.3, {}});
    p.series.push_back(Series{"", "#1f77b4", Style::line, {0, 1}, {1, 0}, {}, false, 1.3, {}});
    f.panels.push_back(std::move(p));
  }
  const std::string svg = render_svg(f);
  std::size_t entries = 0;
  for (auto at = svg.find(">recorded<"); at != std::string::npos; at = svg.find(">recorded<", at + 1)) ++entries;
  EXPECT_EQ(entries, 1u);
}

TEST(Files, EachFigureGetsADescriptiveFileOfItsOwn) {
  Figure a, b, c;
  a.name = "op1*_levels";
  b.name = "op1*_levels";
  c.name = "bode_op2";
  const auto files = svg_files("plots", {a, b, c});
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].first, std::filesystem::path("plots/op1__levels.svg"));
  EXPECT_EQ(files[1].first, std::filesystem::path("plots/op1__levels_2.svg"));
  EXPECT_EQ(files[2].first, std::filesystem::path("plots/bode_op2.svg"));
  EXPECT_EQ(files[2].second.rfind("<?xml", 0), 0u);
  EXPECT_EQ(unbalanced_tags(files[2].second), "");
}

}  // namespace
