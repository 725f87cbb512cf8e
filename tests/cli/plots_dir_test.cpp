// --plots-dir DIR: reproduce, calibrate, diagnose and linearize write every plot as a standalone SVG
// in DIR, created when missing, in the same all-or-nothing set as their other outputs: a failing
// run leaves the files DIR already holds as they were and adds none.
#include <gtest/gtest.h>

#include <cmath>

#include "testing/cli_run.hpp"
#include "testing/svg_checks.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

std::vector<std::string> svg_names(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".svg") out.push_back(e.path().filename().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool has_name_ending(const std::vector<std::string>& names, const std::string& end) {
  return std::any_of(names.begin(), names.end(), [&](const std::string& n) {
    return n.size() >= end.size() && n.compare(n.size() - end.size(), end.size(), end) == 0;
  });
}

void expect_standalone_svg(const fs::path& file) {
  const std::string svg = read_text(file);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u) << file;
  EXPECT_EQ(canalsim::plot_test::unbalanced_tags(svg), "") << file;
  EXPECT_EQ(svg.find("nan"), std::string::npos) << file;
}

TEST(PlotsDir, EveryCommandListsItsPlotsInItsHelp) {
  const fs::path scratch = scratch_dir("plots_help");
  for (const std::string command : {"reproduce", "calibrate", "diagnose", "linearize"}) {
    const RunResult r = run_canalsim(command + " --help", scratch);
    EXPECT_NE(r.out.find("--plots-dir"), std::string::npos) << command;
    EXPECT_NE(r.out.find(".svg"), std::string::npos) << command;
  }
  fs::remove_all(scratch);
}

TEST(PlotsDir, LinearizeWritesItsBodePlotIntoADirectoryItCreates) {
  const fs::path scratch = scratch_dir("plots_linearize");
  const RunResult r = run_canalsim("linearize lab -e op2 --freq 0.01:1:40 --plots-dir plots/new --json g.json", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(svg_names(scratch / "plots" / "new"), std::vector<std::string>{"bode_op2_y_dwe_per_gate.svg"});
  const fs::path file = scratch / "plots" / "new" / "bode_op2_y_dwe_per_gate.svg";
  expect_standalone_svg(file);
  const std::string svg = read_text(file);
  EXPECT_NE(svg.find(">gain [dB]<"), std::string::npos);
  EXPECT_NE(svg.find(">phase [deg]<"), std::string::npos);
  EXPECT_NE(svg.find(">ω [rad/s]<"), std::string::npos);
  EXPECT_TRUE(fs::exists(scratch / "g.json"));
  fs::remove_all(scratch);
}

TEST(PlotsDir, AFailingRunLeavesTheDirectorysFilesUntouchedAndWritesNothing) {
  const fs::path scratch = scratch_dir("plots_failing");
  const fs::path dir = scratch / "plots";
  fs::create_directories(dir);
  std::ofstream(dir / "bode_op2_y_dwe_per_gate.svg") << "an earlier plot\n";
  std::ofstream(dir / "notes.txt") << "mine\n";
  // The work fails: no such experiment.
  RunResult r = run_canalsim("linearize lab -e op9 --plots-dir plots --json g.json", scratch);
  EXPECT_TRUE(is_one_error_line(r)) << r.err;
  // The write fails: one of the set's files cannot be replaced (a directory stands in its place),
  // so neither the other plots nor the JSON are written.
  fs::create_directories(scratch / "blocked" / "bode_op2_y_dwe_per_gate.svg");
  r = run_canalsim("linearize lab -e op2 --freq 0.01:1:20 --plots-dir blocked --json g.json", scratch);
  EXPECT_NE(r.code, 0);
  EXPECT_FALSE(fs::exists(scratch / "g.json"));
  EXPECT_EQ(read_text(dir / "bode_op2_y_dwe_per_gate.svg"), "an earlier plot\n");
  EXPECT_EQ(read_text(dir / "notes.txt"), "mine\n");
  EXPECT_EQ(entry_count(dir), 2u);
  // A DIR that cannot be made is refused before the work.
  std::ofstream(scratch / "a_file") << "x\n";
  r = run_canalsim("linearize lab -e op2 --plots-dir a_file/plots", scratch);
  EXPECT_TRUE(is_one_error_line(r)) << r.err;
  EXPECT_NE(r.err.find("--plots-dir"), std::string::npos) << r.err;
  fs::remove_all(scratch);
}

// A recording of a first-order lag driven by a square-wave command (as diagnose_test's).
void write_lag_recording(const fs::path& file) {
  std::ofstream out(file);
  out.precision(17);
  out << "t_s,u_mm,y_up_mm,y_dwe_mm\n";
  const double h = 0.13, a = std::exp(-h / 2.0);
  double x = 0.0;
  for (int k = 0; k < 1200; ++k) {
    const double t = h * k;
    const double u = k < 20 || std::sin(2.0 * 3.14159265358979 * t / 23.0) < 0.0 ? 17.55 : 27.56;
    out << t << "," << u << "," << 60.0 << "," << 45.0 + x + 0.01 * std::sin(1.7 * k) << "\n";
    x = a * x + (1.0 - a) * 0.8 * (u - 17.55);
  }
}

TEST(PlotsDir, DiagnoseWritesTheReportsFiguresAsFiles) {
  const fs::path scratch = scratch_dir("plots_diagnose");
  write_lag_recording(scratch / "lag.csv");
  const RunResult r = run_canalsim(
      "diagnose --model liom lag.csv --candidates flow_regime_switch --threads 1 --report d.html --plots-dir plots", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> names = svg_names(scratch / "plots");
  for (const char* end : {"_levels_and_residual.svg", "_residual_autocorrelation.svg", "_step_zoom.svg"}) {
    EXPECT_TRUE(has_name_ending(names, end)) << end;
  }
  for (const auto& n : names) expect_standalone_svg(scratch / "plots" / n);
  // The report draws the same figures inline.
  const std::string html = read_text(scratch / "d.html");
  EXPECT_NE(html.find(">residual [mm]<"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  fs::remove_all(scratch);
}

}  // namespace
