// `canalsim linearize`: bad choices fail with one line naming the flag and what is allowed, and
// leave an existing output untouched; a good run writes the grid it was asked for.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Linearize, BadChoicesFailWithOneLineAndWriteNothing) {
  const fs::path scratch = scratch_dir("linearize_bad");
  {
    std::ofstream keep(scratch / "keep.json");
    keep << "old\n";
  }
  std::vector<std::pair<std::string, std::string>> cases = {
      {"lab -e op2 --freq 0:1:10", "--freq = '0:1:10': the frequencies must be positive"},
      {"lab -e op2 --freq 1:2:0", "--freq = '1:2:0': N must be a whole number >= 1"},
      {"lab -e op2 --freq 1:1e4:10", "is beyond the grid's Nyquist frequency"},
      {"lab -e op2 --input inflow", "--input inflow: scenario 'lab' has no imposed inflow"},
      {"lab -e op2 --input offtake:1", "--input offtake:1: scenario 'lab' has no offtake"},
      {"lab -e op2 --input valve", "--input = 'valve': expected gate, inflow or offtake:I"},
      {"lab -e op2 --output y_check2", "--output y_check2: scenario 'lab' has pools 1..1"},
      {"lab -e op9", "--experiment op9: scenario 'lab' has no such experiment"},
  };
  {
    // A pool filled through a closed end has no steady state.
    std::ofstream toml(scratch / "filling.toml");
    toml << "name = \"filling\"\n[upstream]\nkind = \"discharge\"\ndischarge_m3s = 0.01\n[[pools]]\n"
            "length_m = 10.0\nbottom_width_m = 0.2\nwall_height_m = 0.5\ncells = 50\ninitial_depth_m = 0.1\n"
            "[downstream]\nkind = \"closed\"\n[[experiments]]\nname = \"fill\"\n[experiments.input]\n"
            "kind = \"constant\"\n";
  }
  cases.emplace_back("filling.toml -e fill --input inflow", "experiment 'fill': no steady state at the operating point");
  for (const auto& [args, message] : cases) {
    const RunResult r = run_canalsim("linearize " + args + " --json keep.json", scratch);
    EXPECT_TRUE(fails_naming(r, message)) << args;
    EXPECT_EQ(read_text(scratch / "keep.json"), "old\n") << args;
  }
  fs::remove_all(scratch);
}

TEST(Linearize, WritesTheResponseOnTheRequestedGrid) {
  const fs::path scratch = scratch_dir("linearize_good");
  const RunResult r = run_canalsim("linearize lab -e op2 --freq 0.01:10:50 --json r.json --csv r.csv", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_text(scratch / "r.json"));
  ASSERT_EQ(j["response"].size(), 50u);
  EXPECT_DOUBLE_EQ(j["response"][0]["omega_rad_s"].get<double>(), 0.01);
  EXPECT_NEAR(j["response"][49]["omega_rad_s"].get<double>(), 10.0, 1e-9);
  EXPECT_GT(j["static_gain"].get<double>(), 0.0);  // opening the head gate raises the pool
  EXPECT_EQ(j["input"]["unit"], "m");
  const std::string csv = read_text(scratch / "r.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "omega_rad_s,gain,phase_deg,real,imag");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 51);
  fs::remove_all(scratch);
}

}  // namespace

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(FitFreqCheck, ComparesTheFittedModelWithTheLinearisedPool) {
  const fs::path scratch = scratch_dir("fit_freq_check");
  ASSERT_EQ(run_canalsim("simulate lab -e op2 -o op2.csv", scratch).code, 0);
  const RunResult wrong = run_canalsim("fit -m liom op2.csv --freq-check asce2", scratch);
  EXPECT_TRUE(is_one_error_line(wrong)) << wrong.err;
  EXPECT_NE(wrong.err.find("--freq-check: op2.csv comes from experiment 'op2', which scenario 'asce2' does not have"),
            std::string::npos)
      << wrong.err;
  const RunResult r = run_canalsim("fit -m liom op2.csv --freq-check lab --json f.json", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("frequency check against the linearised pool"), std::string::npos) << r.out;
  const auto j = nlohmann::json::parse(read_text(scratch / "f.json"));
  ASSERT_EQ(j["freq_check"].size(), 1u);
  const double error = j["freq_check"][0]["model_vs_pde_rms_relative_error"].get<double>();
  EXPECT_GT(error, 0.0);
  EXPECT_LT(error, 1.0);  // the fitted LIOM is within the PDE's order of magnitude over the band
  fs::remove_all(scratch);
}

}  // namespace
