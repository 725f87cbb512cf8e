// `canalsim fit`: an unwritable --json is refused before any recording is read or fitted; the
// uncertainty index of a parameter whose nominal value is 0 is printed as undefined, not inf%;
// --bounds and --start are checked against the model's parameter names; the table shows whole
// recording names; each parameter comes with its std and the fit with the correlations.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Fit, JsonInAMissingDirectoryIsRefusedBeforeTheRecordingsAreRead) {
  const fs::path scratch = scratch_dir("fit_json");
  // missing.csv would be the error if the recordings were read first.
  expect_refused_writing_nothing(scratch, "fit --model liom missing.csv --json nodir/fit.json",
                                 "--json nodir/fit.json: directory nodir does not exist", {"nodir"});
  fs::remove_all(scratch);
}

// dp (eq. 22) divides by the nominal value. On the simulated lab's op1 and op2 the γ sweep puts
// the nominal NLFOM-S at γ = 0 (as every run of the study does), so its dp is undefined.
TEST(Fit, UncertaintyIndexOfAZeroNominalParameterIsUndefinedNotInfinite) {
  const fs::path scratch = scratch_dir("fit_dp");
  for (const std::string e : {"op1", "op2"}) {
    ASSERT_EQ(run_canalsim("simulate lab -e " + e + " -o " + e + ".csv", scratch).code, 0);
  }
  const RunResult r = run_canalsim("fit --model nlfom-s op1.csv op2.csv --nominal --gamma 0:1:0.5", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.find("inf%"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("nan%"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("gamma undefined (nominal 0)"), std::string::npos) << r.out;
  fs::remove_all(scratch);
}

// A first-order-plus-delay step (K 2, T 20 s, L 1.5 s) sampled at 0.125 s, in closed form.
void write_step_recording(const fs::path& file) {
  std::ofstream out(file);
  out << "t_s,u_mm,y_dwe_mm\n";
  for (int k = 0; k < 1200; ++k) {
    const double t = 0.125 * k, since = t - 5.0 - 1.5;
    const double y = 45.0 + (since > 0 ? 10.0 * (1.0 - std::exp(-since / 20.0)) : 0.0);
    out << t << "," << (t >= 5.0 ? 25 : 20) << "," << y << "\n";
  }
}

// Every fit says how sure it is: the table shows value ± std, the JSON a std per parameter, the
// correlations by name and the autocorrelation inflation; a parameter held by its bounds has std
// 0 and null correlations (JSON has no NaN).
TEST(Fit, TableAndJsonGiveEachParametersStdAndTheirCorrelations) {
  const fs::path scratch = scratch_dir("fit_std");
  write_step_recording(scratch / "step.csv");
  const RunResult r = run_canalsim("fit --model liom step.csv --bounds L=1.5:1.5 --json fit.json", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(" ± "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1.5 (± n/a)"), std::string::npos) << r.out;
  std::ifstream in(scratch / "fit.json");
  const auto fit = nlohmann::json::parse(in)["fits"][0];
  EXPECT_GT(fit["std"]["K"].get<double>(), 0.0) << fit["std"].dump();
  EXPECT_GT(fit["std"]["T"].get<double>(), 0.0) << fit["std"].dump();
  EXPECT_EQ(fit["std"]["L"].get<double>(), 0.0) << fit["std"].dump();
  EXPECT_EQ(fit["correlation"]["names"], nlohmann::json({"K", "T", "L"}));
  const auto& m = fit["correlation"]["matrix"];
  EXPECT_EQ(m[0][0].get<double>(), 1.0);
  EXPECT_NEAR(m[0][1].get<double>(), m[1][0].get<double>(), 1e-12);
  EXPECT_TRUE(m[0][2].is_null()) << m.dump();
  EXPECT_GE(fit["inflation"].get<double>(), 1.0);
  fs::remove_all(scratch);
}

TEST(Fit, BoundsAndStartNameTheModelsParametersAndBadOnesAreOneLineErrors) {
  const fs::path scratch = scratch_dir("fit_bounds");
  write_step_recording(scratch / "step.csv");
  const RunResult ok = run_canalsim("fit --model liom step.csv --bounds T=1:100,L=0:10 --start T=5", scratch);
  EXPECT_EQ(ok.code, 0) << ok.err;
  const RunResult pinned = run_canalsim("fit --model liom step.csv --bounds T=5:6", scratch);
  EXPECT_EQ(pinned.code, 0) << pinned.err;
  EXPECT_NE(pinned.out.find("  6 ± "), std::string::npos) << pinned.out;  // T on its upper bound
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--bounds lambda=0:1", "liom has no parameter lambda (expected K, T, L)"},
      {"--bounds T=5", "expected LO:HI"},
      {"--bounds T=a:5", "'a' is not a finite number"},
      {"--bounds T=5:1", "lower bound above upper bound"},
      {"--bounds T", "expected NAME=LO:HI"},
      {"--start T=1,T=2", "parameter T given twice"},
      {"--start Q=1", "liom has no parameter Q"},
      {"--bounds T=1:10 --start T=50", "bounds.T: initial value 50 lies outside [1, 10]"}};
  for (const auto& [flags, message] : bad) {
    const RunResult r = run_canalsim("fit --model liom step.csv " + flags, scratch);
    EXPECT_TRUE(fails_naming(r, message));
  }
  fs::remove_all(scratch);
}

TEST(Fit, TheTableShowsWholeRecordingNames) {
  const fs::path scratch = scratch_dir("fit_names");
  const std::string name = "pool3_gate_step_2026-11-20_run07_decimated_0.125s.csv";
  write_step_recording(scratch / name);
  fs::create_directory(scratch / "other");
  write_step_recording(scratch / "other" / name);
  const RunResult r = run_canalsim("fit --model liom " + name + " other/" + name, scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("  " + name + " "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  other/" + name + " "), std::string::npos) << r.out;
  fs::remove_all(scratch);
}

// A command in encoder counts of 0.13 mm: K is reported in mm/counts, the same gain as the
// recording in millimetres (K 2 mm/mm = 0.26 mm/count).
TEST(Fit, KIsReportedInTheRecordingsDeclaredUnits) {
  const fs::path scratch = scratch_dir("fit_units");
  write_step_recording(scratch / "mm.csv");
  {
    std::ifstream in(scratch / "mm.csv");
    std::ofstream out(scratch / "counts.csv");
    out << "# u_unit: counts\n# u_scale_mm_per_unit: 0.13\n";
    std::string line;
    std::getline(in, line);
    out << line << "\n";
    while (std::getline(in, line)) {
      const auto a = line.find(','), b = line.find(',', a + 1);
      const double u = std::stod(line.substr(a + 1, b - a - 1));
      out << line.substr(0, a) << "," << u / 0.13 << line.substr(b) << "\n";
    }
  }
  const RunResult r = run_canalsim("fit --model liom counts.csv --json fit.json", scratch);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("K in mm/counts"), std::string::npos) << r.out;
  const std::string json = read_text(scratch / "fit.json");
  const auto at = json.find("\"K_declared_units\": ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_NEAR(std::stod(json.substr(at + 20)), 0.26, 0.26 * 0.03) << json.substr(at, 60);
  fs::remove_all(scratch);
}

// A field logger's own file: its own column names and SI units (a level in m, the gate in m),
// read through --columns and --units, fits the closed-form step (K 2, T 20 s, L 1.5 s) as the
// same data in canalsim's format does; a mapped column the header lacks, a name canalsim does not
// know and a unit it does not know are one-line errors naming them.
TEST(Fit, AUsersOwnColumnNamesAndSiUnitsAreReadThroughColumnsAndUnits) {
  const fs::path scratch = scratch_dir("fit_own_columns");
  {
    std::ofstream out(scratch / "field.csv");
    out << "time,gate,level\n";
    for (int k = 0; k < 1200; ++k) {
      const double t = 0.125 * k, since = t - 5.0 - 1.5;
      const double y_mm = 45.0 + (since > 0 ? 10.0 * (1.0 - std::exp(-since / 20.0)) : 0.0);
      out << t << "," << (t >= 5.0 ? 0.025 : 0.020) << "," << y_mm / 1000.0 << "\n";
    }
  }
  const RunResult refused = run_canalsim("fit --model liom field.csv", scratch);
  EXPECT_EQ(refused.code, 1);
  EXPECT_NE(refused.err.find("missing required column t_s"), std::string::npos) << refused.err;

  const RunResult r =
      run_canalsim("fit --model liom field.csv --columns t=time,u=gate,y_dwe=level --units u=m,y=m --json fit.json", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json fit = nlohmann::json::parse(read_text(scratch / "fit.json"));
  const nlohmann::json& p = fit.at("fits").at(0).at("parameters");
  EXPECT_NEAR(p["K"].get<double>(), 2.0, 0.02) << fit.dump();
  EXPECT_NEAR(p["T"].get<double>(), 20.0, 0.4) << fit.dump();
  EXPECT_NEAR(p["L"].get<double>(), 1.5, 0.15) << fit.dump();

  const RunResult missing = run_canalsim("fit --model liom field.csv --columns t=time,u=gate,y_dwe=lvl", scratch);
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("field.csv:1: no column lvl to read as y_dwe_mm (the header has time, gate, level)"),
            std::string::npos) << missing.err;
  const RunResult unknown = run_canalsim("fit --model liom field.csv --columns z=time", scratch);
  EXPECT_EQ(unknown.code, 1);
  EXPECT_NE(unknown.err.find("--columns z=time: expected NAME=COLUMN"), std::string::npos) << unknown.err;
  const RunResult feet = run_canalsim("fit --model liom field.csv --columns t=time,u=gate,y_dwe=level --units y=ft", scratch);
  EXPECT_EQ(feet.code, 1);
  EXPECT_NE(feet.err.find("--units y=ft: expected"), std::string::npos) << feet.err;
  fs::remove_all(scratch);
}

// A logger's jittered time stamps: fit refuses them with a message that names `canalsim
// resample`; resample writes a uniform recording that fit then reads.
TEST(Fit, JitteredTimeStampsSuggestResampleWhichMakesThemFittable) {
  const fs::path scratch = scratch_dir("fit_jitter");
  {
    std::ofstream out(scratch / "jitter.csv");
    out << "t_s,u_mm,y_dwe_mm\n";
    double t = 0.0;
    for (int k = 0; k < 4000; ++k, t += (k % 3 == 0 ? 0.009 : 0.0105)) {
      const double since = t - 5.0 - 1.5;
      out << t << "," << (t >= 5.0 ? 25 : 20) << "," << 45.0 + (since > 0 ? 10.0 * (1.0 - std::exp(-since / 8.0)) : 0.0) << "\n";
    }
  }
  const RunResult refused = run_canalsim("fit --model liom jitter.csv", scratch);
  EXPECT_TRUE(fails_naming(refused, "not uniformly sampled"));
  EXPECT_NE(refused.err.find("canalsim resample jitter.csv -o uniform.csv --period 0.01"), std::string::npos) << refused.err;
  const RunResult resampled = run_canalsim("resample jitter.csv -o uniform.csv --period 0.05", scratch);
  EXPECT_EQ(resampled.code, 0) << resampled.err;
  const RunResult fitted = run_canalsim("fit --model liom uniform.csv", scratch);
  EXPECT_EQ(fitted.code, 0) << fitted.err;
  const RunResult bad = run_canalsim("resample jitter.csv -o x.csv --period 0", scratch);
  EXPECT_TRUE(is_one_error_line(bad)) << bad.err;
  EXPECT_FALSE(fs::exists(scratch / "x.csv"));
  fs::remove_all(scratch);
}

}  // namespace
