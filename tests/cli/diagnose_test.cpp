// `canalsim diagnose` rejects bad arguments and unreadable recordings with one error line and a
// non-zero exit, and writes no output file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>

#include "scenarios/scenario_toml.hpp"
#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Diagnose, NeitherOrBothOfScenarioAndModelIsOneErrorLine) {
  const fs::path scratch = scratch_dir("diagnose_choice");
  const fs::path rec = scratch / "rec.csv";
  std::ofstream(rec) << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,25,45\n0.26,25,45.1\n";
  for (const std::string& args : {"diagnose " + rec.string(), "diagnose --scenario lab --model liom " + rec.string()}) {
    const RunResult r = run_canalsim(args, scratch);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("exactly one of --scenario"), std::string::npos) << r.err;
  }
  fs::remove_all(scratch);
}

TEST(Diagnose, AnUnknownModelOrAMissingRecordingIsOneErrorLineAndWritesNoJson) {
  const fs::path scratch = scratch_dir("diagnose_model");
  const fs::path json = scratch / "d.json";
  RunResult r = run_canalsim("diagnose --model nosuch " + (scratch / "x.csv").string() + " --json " + json.string(), scratch);
  EXPECT_NE(r.status, 0);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  r = run_canalsim("diagnose --model liom " + (scratch / "missing.csv").string() + " --json " + json.string(), scratch);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("missing.csv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(json));
  fs::remove_all(scratch);
}

// The first problem is reported, naming the file and line; the second file's problem (and a
// "no recordings given" that would follow from the first) are not printed.
TEST(Diagnose, TwoBadRecordingsGiveOneLineNamingTheFirstFileAndLine) {
  const fs::path scratch = scratch_dir("diagnose_two_bad");
  std::ofstream(scratch / "bad1.csv") << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,abc,45\n";
  std::ofstream(scratch / "bad2.csv") << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,25,45\n";
  const RunResult r = run_canalsim("diagnose --scenario lab bad1.csv bad2.csv --json d.json", scratch);
  EXPECT_TRUE(fails_naming(r, "bad1.csv:3"));
  EXPECT_EQ(r.err.find("bad2.csv"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("no recordings given"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch / "d.json"));
  fs::remove_all(scratch);
}

TEST(Diagnose, ARecordingThatDoesNotFitTheScenarioIsOneLineNamingIt) {
  const fs::path scratch = scratch_dir("diagnose_mismatch");
  std::ofstream(scratch / "short.csv") << "t_s,u_mm,y_dwe_mm\n0,20,45\n0.13,25,45\n";
  const RunResult r = run_canalsim("diagnose --scenario lab short.csv short.csv", scratch);
  EXPECT_TRUE(fails_naming(r, "short.csv: 2 samples, expected at least 50"));
  fs::remove_all(scratch);
}

TEST(Diagnose, OutputsInAMissingDirectoryAreRefusedBeforeTheRecordingsAreRead) {
  const fs::path scratch = scratch_dir("diagnose_outputs");
  for (const std::string flag : {"--json", "--report"}) {
    for (const std::string mode : {"--scenario lab", "--model liom"}) {
      const RunResult r = run_canalsim("diagnose " + mode + " missing.csv " + flag + " nodir/out", scratch);
      EXPECT_TRUE(fails_naming(r, flag + " nodir/out: directory nodir does not exist"));
    }
  }
  EXPECT_EQ(entry_count(scratch), 0u);
  fs::remove_all(scratch);
}

// A recording of `rows` samples every `period` s at a constant opening, with a `# scenario:` line.
void write_flat_recording(const fs::path& file, double period, const std::string& canal, int rows = 60) {
  std::ofstream out(file);
  out << "# scenario: " << canal << "\nt_s,u_mm,y_dwe_mm\n";
  for (int k = 0; k < rows; ++k) out << period * k << ",20," << 45 + 0.01 * (k % 7) << "\n";
}

TEST(Diagnose, ABaselineOfAnotherPeriodOrCanalIsOneLineNamingItAndWritesNothing) {
  const fs::path scratch = scratch_dir("diagnose_baseline_bad");
  write_flat_recording(scratch / "rec.csv", 0.13, "lab");
  write_flat_recording(scratch / "base1.csv", 0.13, "lab");
  write_flat_recording(scratch / "base3.csv", 0.26, "lab");
  write_flat_recording(scratch / "other.csv", 0.13, "asce1");
  std::ofstream(scratch / "d.json") << "an earlier result\n";
  const std::size_t before = entry_count(scratch);
  struct Case {
    std::string args, says;
  };
  for (const Case& c :
       {Case{"--baseline base1.csv base3.csv -- rec.csv", "base3.csv: sampled every 0.26 s, the recordings every 0.13 s"},
        Case{"rec.csv --baseline base1.csv other.csv", "other.csv: recorded on canal 'asce1', the recordings on 'lab'"},
        Case{"--baseline base1.csv rec.csv", "diagnose: no recordings to diagnose after the baseline: end the --baseline list with --"}}) {
    const RunResult r = run_canalsim("diagnose --scenario lab " + c.args + " --json d.json --report d.html", scratch);
    EXPECT_TRUE(fails_naming(r, "canalsim: error: " + c.says));
    EXPECT_EQ(read_text(scratch / "d.json"), "an earlier result\n");
    EXPECT_EQ(entry_count(scratch), before);
  }
  const RunResult model = run_canalsim("diagnose --model liom --baseline base1.csv -- rec.csv", scratch);
  EXPECT_TRUE(fails_naming(model, "use it with --scenario"));
  fs::remove_all(scratch);
}

// The lab scenario with op3 shortened to 60 s, and a recording of it.
fs::path short_lab_recording(const fs::path& scratch) {
  std::string toml = run_canalsim("scenarios --show lab", scratch).out;
  const std::string op3 = "name = \"op3\"\n";
  toml.insert(toml.find(op3) + op3.size(), "duration_s = 60.0\n");
  std::ofstream(scratch / "short.toml") << toml;
  const RunResult sim = run_canalsim("simulate short.toml -e op3 -o op3.csv", scratch);
  EXPECT_EQ(sim.code, 0) << sim.err;
  return scratch / "op3.csv";
}

// A fault named on a channel the recordings do not carry, or on one that is no level, is one line
// naming the candidate and the channels there are; nothing is written.
TEST(Diagnose, AChannelTheRecordingsLackIsOneErrorLine) {
  const fs::path scratch = scratch_dir("diagnose_missing_channel");
  short_lab_recording(scratch);
  RunResult r = run_canalsim("diagnose --scenario short.toml op3.csv --candidates sensor_offset[y_check2_mm] --json d.json", scratch);
  EXPECT_TRUE(fails_naming(r, "sensor_offset[y_check2_mm] names channel y_check2_mm"));
  EXPECT_NE(r.err.find("y_dwe_mm, y_dw_mm, y_up_mm"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch / "d.json"));
  r = run_canalsim("diagnose --scenario short.toml op3.csv --candidates sensor_offset[q_lps]", scratch);
  EXPECT_TRUE(fails_naming(r, "unknown effect 'sensor_offset[q_lps]'"));
  fs::remove_all(scratch);
}

TEST(Diagnose, CalibratedScenarioCarriesItsDeviationsAndBaselineRunsInOneCall) {
  const fs::path scratch = scratch_dir("diagnose_baseline_ok");
  short_lab_recording(scratch);
  RunResult r = run_canalsim(
      "calibrate --scenario short.toml op3.csv -o cal.toml --params manning_n,offset_y_dwe_mm --starts 1 --json c.json",
      scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string cal = read_text(scratch / "cal.toml");
  const auto table = cal.find("[calibration.std]");
  ASSERT_NE(table, std::string::npos) << cal;
  const auto manning = cal.find("manning_n = ", table);
  ASSERT_NE(manning, std::string::npos) << cal;
  // What the calibration leaves open for the diagnosis is the statistical deviation: the grid
  // shift is shared by the calibrated model and the diagnosis on its grid (diagnosis/baseline.hpp).
  const nlohmann::json report = nlohmann::json::parse(read_text(scratch / "c.json"));
  for (const auto& p : report["parameters"]) {
    if (p["name"] != "manning_n") continue;
    ASSERT_GT(p["numerical_std"].get<double>(), 0.0) << "the grid check ran";
    const double written = std::stod(cal.substr(manning + std::string("manning_n = ").size()));
    EXPECT_NEAR(written, p["statistical_std"].get<double>(), 1e-5 * written);
    EXPECT_LT(written, p["std"].get<double>());
  }
  EXPECT_NE(cal.find("offset_y_dwe_mm = ", table), std::string::npos) << cal;
  EXPECT_NE(cal.find("[calibration]"), std::string::npos) << cal;
  EXPECT_NE(cal.find("baseline_rms_mm = "), std::string::npos) << cal;
  // With the other parameter held, a deviation can only shrink: σ_i / sqrt((R⁻¹)_ii), (R⁻¹)_ii ≥ 1.
  const canalsim::scenarios::Scenario calibrated = canalsim::scenarios::parse_scenario(cal, "cal.toml");
  ASSERT_EQ(calibrated.calibrated_std_alone.size(), calibrated.calibrated_std.size()) << cal;
  for (const auto& [name, alone] : calibrated.calibrated_std_alone) {
    EXPECT_LE(alone, calibrated.calibrated_std.at(name) * (1.0 + 1e-9)) << name;
    EXPECT_GT(alone, 0.0) << name;
  }
  // The residual left per level channel; the primary's is the one in [calibration].
  ASSERT_TRUE(calibrated.calibrated_baseline_rms_by_channel.count("y_dwe_mm")) << cal;
  EXPECT_NEAR(calibrated.calibrated_baseline_rms_by_channel.at("y_dwe_mm"), calibrated.calibrated_baseline_rms_mm,
              1e-5 * calibrated.calibrated_baseline_rms_mm);

  r = run_canalsim("diagnose --scenario cal.toml op3.csv --candidates sensor_offset --json d.json", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(read_text(scratch / "d.json").find("\"verdict\""), std::string::npos);

  // A name that is no parameter of the canal: one line naming the file and the key.
  std::ofstream(scratch / "bad.toml") << cal << "cd_fre = 0.1\n";
  r = run_canalsim("diagnose --scenario bad.toml op3.csv --candidates sensor_offset", scratch);
  EXPECT_TRUE(fails_naming(r, "bad.toml: calibration.std_alone.cd_fre: not a calibration parameter of lab"));

  r = run_canalsim("diagnose --scenario short.toml op3.csv --candidates sensor_offset --json b.json --baseline op3.csv", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("calibrated on 1 baseline recording(s): op3.csv"), std::string::npos) << r.out;
  const std::string json = read_text(scratch / "b.json");
  const auto baseline = json.find("\"baseline\": {");
  ASSERT_NE(baseline, std::string::npos) << json;
  for (const char* field : {"\"files\": [", "\"parameters\": [", "\"residual_before\"", "\"residual_after\"",
                            "\"name\": \"cd_free\"", "\"std\""}) {
    EXPECT_NE(json.find(field, baseline), std::string::npos) << field;
  }
  fs::remove_all(scratch);
}

}  // namespace

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

// A pool driven across the flow-regime border (eq. 23: at y_up = 60 mm, y_dwe = 45 mm the border
// is at a 22.5 mm opening): the command steps between 135 and 212 encoder counts of 0.13 mm, the
// upstream level swings by ±5 mm, the level follows a first-order lag (K 0.8, T 2 s). Written
// once in millimetres and once in counts with the declaration `canalsim fit` honours.
void write_regime_recordings(const fs::path& dir) {
  std::ofstream mm(dir / "mm.csv"), counts(dir / "counts.csv");
  mm.precision(17);
  counts.precision(17);
  counts << "# u_unit: counts\n# u_scale_mm_per_unit: 0.13\n";
  mm << "t_s,u_mm,y_up_mm,y_dwe_mm\n";
  counts << "t_s,u_mm,y_up_mm,y_dwe_mm\n";
  const double h = 0.13, a = std::exp(-h / 2.0);
  double x = 0.0;
  for (int k = 0; k < 1500; ++k) {
    const double t = h * k;
    const int c = k < 20 || std::sin(2.0 * 3.14159265358979 * t / 23.0) < 0.0 ? 135 : 212;
    const double u = 0.13 * c, y_up = 60.0 + 5.0 * std::sin(2.0 * 3.14159265358979 * t / 70.0);
    const double y = 45.0 + x + 0.01 * std::sin(1.7 * k);
    mm << t << "," << u << "," << y_up << "," << y << "\n";
    counts << t << "," << c << "," << y_up << "," << y << "\n";
    x = a * x + (1.0 - a) * 0.8 * (u - 0.13 * 135);
  }
}

double parameter_value(const std::string& json, const std::string& name, std::string& unit) {
  const auto at = json.find("\"" + name + "\": {");
  if (at == std::string::npos) return std::nan("");
  const auto unit_at = json.find("\"unit\": \"", at);
  unit = json.substr(unit_at + 9, json.find('"', unit_at + 9) - unit_at - 9);
  const auto value_at = json.find("\"value\": ", at);
  return std::stod(json.substr(value_at + 9));
}

// diagnose --model reports its gains in the recording's declared units, as fit does: the
// submerged-flow gain of the regime switch in mm/counts is the mm/mm one times 0.13 mm/count.
TEST(Diagnose, ModelGainsAreReportedInTheRecordingsDeclaredUnits) {
  const fs::path scratch = scratch_dir("diagnose_units");
  write_regime_recordings(scratch);
  const std::string flags = " --candidates flow_regime_switch --threads 1";
  const RunResult in_mm = run_canalsim("diagnose --model liom mm.csv --json mm.json" + flags, scratch);
  const RunResult in_counts = run_canalsim("diagnose --model liom counts.csv --json counts.json --report counts.html" + flags, scratch);
  ASSERT_EQ(in_mm.code, 0) << in_mm.err;
  ASSERT_EQ(in_counts.code, 0) << in_counts.err;
  std::string unit_mm, unit_counts;
  const double k_mm = parameter_value(read_text(scratch / "mm.json"), "K_sub", unit_mm);
  const double k_counts = parameter_value(read_text(scratch / "counts.json"), "K_sub", unit_counts);
  EXPECT_EQ(unit_mm, "mm/mm");
  EXPECT_EQ(unit_counts, "mm/counts");
  ASSERT_TRUE(std::isfinite(k_mm) && k_mm != 0.0) << read_text(scratch / "mm.json");
  EXPECT_NEAR(k_counts, 0.13 * k_mm, 1e-6 * std::abs(k_mm));
  EXPECT_NE(read_text(scratch / "counts.html").find("mm/counts"), std::string::npos);
  fs::remove_all(scratch);
}

}  // namespace
