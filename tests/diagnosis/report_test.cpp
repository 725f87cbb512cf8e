// Reports: the JSON carries every field docs/diagnosis.md lists; the HTML page is self-contained.
#include "diagnosis/report.hpp"

#include <gtest/gtest.h>

#include "plot/palette.hpp"
#include "testing/svg_checks.hpp"

namespace canalsim::diagnosis {
namespace {

Diagnosis sample() {
  Diagnosis d;
  d.verdict = "sensor_offset";
  d.reason = "test";
  EffectResult e;
  e.name = "sensor_offset";
  e.score = 0.9;
  e.significant = true;
  e.parameter = {"offset", "mm", 1.5, 0.01};
  e.nrmse_before = 60.0;
  e.nrmse_after = 95.0;
  e.heldout_nrmse_before = 58.0;
  e.heldout_nrmse_after = 94.0;
  d.effects.push_back(e);
  RecordingSeries s;
  s.name = "op1.csv";
  for (int k = 0; k < 10; ++k) {
    s.t.push_back(k);
    s.u.push_back(20);
    s.recorded.push_back(41.5);
    s.nominal.push_back(40.0);
    s.corrected.push_back(41.5);
  }
  s.fit_samples = 5;
  d.series.push_back(s);
  d.mismatch.windows.push_back({"op1.csv", 1.0, 3.0, 1.5, 1.6, {"after_gate_move"}});
  d.mismatch.by_recording.push_back({"op1.csv", 15.0, 60.0, 1.5, 1.5, 0.0, false, true, {}});
  d.mismatch_after.by_recording.push_back({"op1.csv", 15.0, 95.0, 0.05, 0.0, 0.0, true, true, {}});
  d.mismatch.by_regime.push_back({"submerged", 10, 1.5, 1.5});
  return d;
}

TEST(Report, JsonHasTheFieldsOfTheIssue) {
  const nlohmann::json j = to_json(sample());
  EXPECT_EQ(j["verdict"], "sensor_offset");
  const auto& e = j["effects"][0];
  for (const char* key : {"name", "score", "parameters", "nrmse_before", "nrmse_after", "heldout_nrmse_before",
                          "heldout_nrmse_after"}) {
    EXPECT_TRUE(e.contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(e["parameters"]["offset"]["value"].get<double>(), 1.5);
  for (const char* key : {"windows", "band_hz", "by_recording", "by_regime"}) {
    EXPECT_TRUE(j["mismatch"].contains(key)) << key;
  }
  EXPECT_TRUE(j["mismatch"]["band_hz"].is_null());
  EXPECT_EQ(j["mismatch"]["windows"][0]["events"][0], "after_gate_move");
}

TEST(Report, HtmlIsOneSelfContainedPage) {
  const std::string html = html_report(sample(), "t");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("Verdict: sensor_offset"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("https:"), std::string::npos);
}

TEST(Report, TheFiguresShowTheMismatchWindowsAndTheCorrectedModel) {
  const std::vector<plot::Figure> figures = report_figures(sample());
  ASSERT_EQ(figures.size(), 2u);  // the command never changes: no step zoom
  EXPECT_EQ(figures[0].name, "op1_csv_levels_and_residual");
  EXPECT_EQ(figures[1].name, "op1_csv_residual_autocorrelation");
  EXPECT_EQ(figures[0].panels[0].series.size(), 3u);  // recorded, nominal, corrected
  EXPECT_EQ(figures[0].panels[1].windows.size(), 1u);
  EXPECT_EQ(figures[0].panels[1].y.title(), "residual [mm]");
}

// A clean diagnosis: the model explains the recording, the residual is flat. It must look clean: a
// calm symmetric range around zero, no shaded windows, no corrected model, no "-0" tick.
TEST(Report, ACleanDiagnosisLooksClean) {
  Diagnosis d = sample();
  d.verdict = "none";
  for (auto& s : d.series) {
    s.nominal = s.recorded;
    s.corrected = s.recorded;
    s.u[6] = 25;  // one command change
  }
  const std::vector<plot::Figure> figures = report_figures(d);
  ASSERT_EQ(figures.size(), 3u);
  EXPECT_EQ(figures[2].name, "op1_csv_step_zoom");
  const plot::Figure& levels = figures[0];
  EXPECT_EQ(levels.panels[0].series.size(), 2u);  // recorded and nominal
  EXPECT_TRUE(levels.panels[1].windows.empty());
  const plot::PanelFrame residual = plot::layout(levels)[1];
  EXPECT_DOUBLE_EQ(residual.y.low, -0.5);
  EXPECT_DOUBLE_EQ(residual.y.high, 0.5);
  EXPECT_EQ(residual.y.ticks, (std::vector<double>{-0.5, 0.0, 0.5}));
  for (const auto& f : figures) {
    const std::string svg = plot::render_svg(f);
    EXPECT_EQ(plot_test::unbalanced_tags(svg), "") << f.name;
    for (const auto& text : plot_test::text_nodes(svg)) EXPECT_FALSE(plot_test::is_negative_zero(text)) << f.name << ": " << text;
    EXPECT_EQ(svg.find(plot::kWindowShade), std::string::npos) << f.name;
  }
}

TEST(Report, TextSummaryStartsWithTheVerdict) {
  EXPECT_EQ(text_summary(sample()).rfind("verdict: sensor_offset", 0), 0u);
}

}  // namespace
}  // namespace canalsim::diagnosis
