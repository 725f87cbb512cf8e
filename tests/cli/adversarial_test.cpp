// What an adversarial user tries with every subcommand, and what must happen: a value that is not
// what the key says is an error naming it (never silently replaced by a default that changes the
// result), outputs are one transaction that never overwrites an input or a device, every search
// ends, and no degenerate input prints -inf or a diverged model with exit status 0.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <functional>
#include <regex>
#include <sys/stat.h>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

// One simulated recording of the lab's op1 per test program, copied into each test's scratch.
const std::string& op1_text() {
  static const std::string text = [] {
    const fs::path scratch = scratch_dir("adversarial_op1");
    const RunResult r = run_canalsim("simulate lab -e op1 -o op1.csv", scratch);
    EXPECT_EQ(r.code, 0) << r.err;
    std::string t = read_text(scratch / "op1.csv");
    fs::remove_all(scratch);
    return t;
  }();
  return text;
}

// op1 with a metadata line added before the header (or replacing a key's line).
std::string with_metadata(const std::string& line) {
  std::string text = op1_text();
  const std::string key = line.substr(0, line.find(':') + 1);
  const auto at = text.find(key);
  if (at != std::string::npos) return text.replace(at, text.find('\n', at) - at, line);
  return text.insert(text.find("t_s,"), line + "\n");
}

// op1 with `edit` applied to each data row's fields (header order).
std::string with_rows(const std::function<void(std::vector<std::string>&, std::size_t)>& edit, std::size_t rows = 0) {
  const std::string text = op1_text();
  const auto header = text.find("t_s,");
  std::istringstream in(text.substr(header));
  std::string line, out = text.substr(0, header);
  std::getline(in, line);
  out += line + "\n";
  for (std::size_t k = 0; std::getline(in, line) && (rows == 0 || k < rows); ++k) {
    std::vector<std::string> f;
    std::stringstream split(line);
    for (std::string x; std::getline(split, x, ',');) f.push_back(x);
    edit(f, k);
    for (std::size_t i = 0; i < f.size(); ++i) out += (i ? "," : "") + f[i];
    out += "\n";
  }
  return out;
}

constexpr std::size_t kDownstreamLevel = 5;  // y_dwe_mm's column in a simulated recording

bool prints_non_finite(const std::string& text) {
  return std::regex_search(text, std::regex(R"((^|[^A-Za-z])-?(nan|inf)([^A-Za-z]|$))", std::regex::icase));
}

// Every key of the metadata is checked where the recording is read: the diagnosis would say
// `unexplained` on op1 with the operating opening ignored, `none` with it read.
TEST(Adversarial, MetadataThatIsNotWhatItsKeySaysIsOneErrorNamingFileAndKey) {
  const fs::path scratch = scratch_dir("adv_metadata");
  const struct {
    std::string line, expected;
  } cases[] = {
      {"# operating_opening_mm: fifteen", "metadata operating_opening_mm: 'fifteen': expected a number of mm in [0, 100000]"},
      {"# operating_opening_mm: nan", "metadata operating_opening_mm: 'nan'"},
      {"# operating_opening_mm: 1e300", "metadata operating_opening_mm: '1e300'"},
      {"# operating_opening_mm: -5", "metadata operating_opening_mm: '-5'"},
      {"# initial_y_up_mm: nan", "metadata initial_y_up_mm: 'nan'"},
      {"# u_scale_mm_per_unit: 1e300", "metadata u_scale_mm_per_unit: '1e300'"},
      {"# y_scale_mm_per_unit: 1e-300", "metadata y_scale_mm_per_unit: '1e-300'"},
      {"# sampling_period_s: 0.5", "metadata sampling_period_s: 0.5 s contradicts the t_s step of 0.13 s"},
      {"# experiment: op2", "metadata experiment given twice"},
  };
  for (const auto& c : cases) {
    std::string text = with_metadata(c.line);
    if (c.line == "# experiment: op2") text = "# experiment: op2\n" + op1_text();
    std::ofstream(scratch / "bad.csv") << text;
    for (const std::string command : {"fit -m nlfom-s bad.csv", "fit -m hybrid bad.csv", "diagnose --model lfom bad.csv",
                                      "diagnose --scenario lab bad.csv", "calibrate --scenario lab bad.csv -o c.toml"}) {
      const RunResult r = run_canalsim(command, scratch);
      EXPECT_TRUE(fails_naming(r, "bad.csv:"));
      EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.line << " | " << command << ": " << r.err;
    }
  }
  EXPECT_FALSE(fs::exists(scratch / "c.toml"));
  fs::remove_all(scratch);
}

// Two outputs naming one file lose one of them; an output naming an input destroys it; a device
// or FIFO replaced by a file breaks the system. All refused before any work, touching nothing.
TEST(Adversarial, OutputsThatWouldCollideOrOverwriteAnInputAreRefusedBeforeAnyWork) {
  const fs::path scratch = scratch_dir("adv_outputs");
  std::ofstream(scratch / "op1.csv") << op1_text();
  ASSERT_EQ(::mkfifo((scratch / "fifo").c_str(), 0600), 0);
  fs::create_symlink("/proc/self/fd/1", scratch / "to_stdout");
  const struct {
    std::string command, expected;
  } cases[] = {
      {"fit -m liom op1.csv --json op1.csv", "--json op1.csv: the same file as the recording op1.csv"},
      {"resample op1.csv -o ./op1.csv --period 0.26", "-o ./op1.csv: the same file as the recording op1.csv"},
      {"linearize lab -e op1 --csv x.out --json x.out", "--csv x.out: the same file as --json x.out"},
      {"calibrate --scenario lab op1.csv -o c.toml --json c.toml", "--json c.toml: the same file as -o c.toml"},
      {"diagnose --scenario lab op1.csv --json d.json --report d.json", "the same file as --json d.json"},
      {"fit -m liom op1.csv --json /dev/null", "--json /dev/null: is in /dev: expected a regular file"},
      {"fit -m liom op1.csv --json fifo", "--json fifo: is a FIFO"},
      {"fit -m liom op1.csv --json to_stdout", "--json to_stdout: links to /proc/self/fd/1, in /proc"},
      {"prbs -o /dev/null", "-o /dev/null: is in /dev"},
  };
  for (const auto& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const RunResult r = run_canalsim(c.command, scratch);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_TRUE(fails_naming(r, c.expected)) << c.command;
    EXPECT_LT(seconds, 30.0) << c.command << ": refused after the work, not before";
  }
  EXPECT_EQ(read_text(scratch / "op1.csv"), op1_text());
  EXPECT_TRUE(fs::is_fifo(scratch / "fifo"));
  EXPECT_EQ(entry_count(scratch), 3u);  // op1.csv, fifo, to_stdout: nothing written, nothing left
  fs::remove_all(scratch);
}

// calibrate's scenario, JSON and report are one set: a report that cannot be written (a link into
// a missing directory, found only when writing) leaves the scenario and the JSON as they were.
TEST(Adversarial, CalibrateWritesItsOutputsAllOrNothing) {
  const fs::path scratch = scratch_dir("adv_calibrate_set");
  std::ofstream(scratch / "op1.csv") << op1_text();
  std::ofstream(scratch / "cal.toml") << "old scenario\n";
  std::ofstream(scratch / "cal.json") << "old json\n";
  fs::create_symlink("missing/report.html", scratch / "report.html");
  const RunResult r = run_canalsim("calibrate --scenario lab op1.csv -o cal.toml --json cal.json --report report.html "
                                   "--params manning_n --starts 1 --grid-refinements 0",
                                   scratch);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("canalsim: error: missing/report.html: cannot write"), std::string::npos) << r.err;
  EXPECT_EQ(read_text(scratch / "cal.toml"), "old scenario\n");
  EXPECT_EQ(read_text(scratch / "cal.json"), "old json\n");
  EXPECT_EQ(entry_count(scratch), 4u);  // no temporary, no *.bak.* left
  // Written through the link once its directory exists; the link stays.
  fs::create_directory(scratch / "missing");
  const RunResult ok = run_canalsim("calibrate --scenario lab op1.csv -o cal.toml --json cal.json --report report.html "
                                    "--params manning_n --starts 1 --grid-refinements 0",
                                    scratch);
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(fs::is_symlink(scratch / "report.html"));
  EXPECT_NE(read_text(scratch / "missing" / "report.html").find("<html"), std::string::npos);
  EXPECT_NE(read_text(scratch / "cal.toml").find("manning_n"), std::string::npos);
  fs::remove_all(scratch);
}

// Searches that never ended, and a resampling that grew without bound, end within seconds with
// a result or one line.
TEST(Adversarial, EverySearchEndsAndLargeResamplingsAreRefusedUpFront) {
  const fs::path scratch = scratch_dir("adv_bounded");
  std::ofstream(scratch / "op1.csv") << op1_text();
  std::ofstream(scratch / "tiny.csv") << with_rows([](std::vector<std::string>& f, std::size_t) {
    f[kDownstreamLevel] = std::to_string(std::stod(f[kDownstreamLevel]) * 1e-3) + "e-198";
  });
  std::ofstream(scratch / "gap.csv") << with_rows(
      [](std::vector<std::string>& f, std::size_t k) {
        if (k == 9) f[0] = "1e9";
      },
      10);
  const struct {
    std::string command;
    int code;
    std::string expected;
  } cases[] = {
      {"fit -m idz tiny.csv", 1, "tiny.csv: y_dwe_mm varies by only"},
      {"diagnose --model idz tiny.csv", 1, "tiny.csv: y_dwe_mm varies by only"},
      // Bounds that leave one value hold the parameter there.
      {"fit -m lfom --bounds T=0:0 op1.csv", 0, "lfom fits"},
      {"fit -m idz --bounds L=4:4 op1.csv", 0, "idz fits"},
      {"resample op1.csv -o r.csv --period 1e-6", 1, "writes 2.55e+08 rows, expected at most 5e+06"},
      {"resample gap.csv -o r.csv --period 0.13", 1, "expected at most"},
  };
  for (const auto& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const RunResult r = run_canalsim(c.command, scratch);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.code, c.code) << c.command << ": " << r.err;
    if (c.code == 1) {
      EXPECT_TRUE(is_one_error_line(r)) << c.command << ": " << r.err;
    }
    EXPECT_NE((c.code == 0 ? r.out : r.err).find(c.expected), std::string::npos) << c.command << ": " << r.err << r.out;
    EXPECT_FALSE(prints_non_finite(r.out)) << c.command << ": " << r.out;
    EXPECT_LT(seconds, 120.0) << c.command;
  }
  EXPECT_FALSE(fs::exists(scratch / "r.csv"));
  fs::remove_all(scratch);
}

// Inputs whose figures are undefined (a level that never moves, fewer samples than unknowns) or a
// model that diverges are errors, not -inf or a model with an IAE of 1e37 printed as a fit.
TEST(Adversarial, DegenerateInputsAndDivergedModelsAreErrorsNotFigures) {
  const fs::path scratch = scratch_dir("adv_degenerate");
  std::ofstream(scratch / "op1.csv") << op1_text();
  std::ofstream(scratch / "zero.csv") << with_rows([](std::vector<std::string>& f, std::size_t) { f[kDownstreamLevel] = "0"; });
  std::ofstream(scratch / "few.csv") << "t_s,u_mm,y_dwe_mm\n0,10,50\n0.13,20,51\n0.26,10,50.5\n";
  const struct {
    std::string command, expected;
  } cases[] = {
      {"diagnose --scenario lab zero.csv", "zero.csv: y_dwe_mm is 0 mm in every row"},
      {"fit -m lfom few.csv", "few.csv: 3 samples: too few to fit lfom"},
      {"diagnose --model lfom few.csv", "few.csv: 3 samples: too few to fit lfom"},
      {"fit -m nlfom-s --gamma 10:10:1 op1.csv", "does not follow op1.csv"},
      {"blindtest --duration 1e300 --trials 1", "--duration 1e+300: longer than experiment op1"},
  };
  for (const auto& c : cases) {
    const RunResult r = run_canalsim(c.command, scratch);
    EXPECT_TRUE(fails_naming(r, c.expected)) << c.command;
    EXPECT_FALSE(prints_non_finite(r.out)) << c.command << ": " << r.out;
  }
  fs::remove_all(scratch);
}

// A flag that does not apply to the mode chosen would be ignored without a word; a recorded
// upstream level that the recording does not have would silently become the model's supply.
TEST(Adversarial, FlagsThatDoNotApplyAreRefused) {
  const fs::path scratch = scratch_dir("adv_flags");
  std::ofstream(scratch / "op1.csv") << op1_text();
  std::ofstream(scratch / "no_up.csv") << op1_text().substr(0, op1_text().find("t_s,")) +
                                              "t_s,u_mm,y_dwe_mm\n" + [] {
                                                std::string rows;
                                                for (int k = 0; k < 200; ++k) {
                                                  rows += std::to_string(0.13 * k) + "," + (k % 16 < 8 ? "20" : "10") +
                                                          "," + std::to_string(45.0 + 0.01 * (k % 16)) + "\n";
                                                }
                                                return rows;
                                              }();
  const std::vector<ErrorCase> cases = {
      {"diagnose --model lfom op1.csv --recorded-upstream", "diagnose --recorded-upstream: applies to --scenario"},
      {"diagnose --scenario lab op1.csv --quantum 0.05", "diagnose --quantum: applies to --model"},
      {"diagnose --scenario lab no_up.csv --recorded-upstream", "no_up.csv: missing column y_up_mm: --recorded-upstream"},
      {"calibrate --scenario lab no_up.csv -o c.toml --replay recorded-upstream", "no_up.csv: missing column y_up_mm"},
      {"fit -m lfom --memory full --memory-terms 5 op1.csv", "fit --memory-terms: applies to --memory short"},
      {"fit -m lfom --upstream-level 60 op1.csv", "fit --upstream-level: model lfom does not use the upstream level"},
      {"blindtest --quantum 0.1 --trials 1", "blindtest --quantum: applies to --model"},
      {"blindtest --trials 2 --only 2", "blindtest: only = 2: expected a trial index in 0..1"},
      {"blindtest --truth-scheme staggered --trials 1", "blindtest --truth-scheme: applies to --realistic"},
      {"simulate lab -e op1 --scheme upwind -o x.csv", "--scheme: upwind not in {finite-volume,staggered}"},
  };
  expect_errors(cases, scratch);
  fs::remove_all(scratch);
}

// resample writes the period it resampled to where the recording states its period, so that the
// file it writes reads back (the reader refuses a sampling_period_s that contradicts the rows).
TEST(Adversarial, ResampleUpdatesTheStatedSamplingPeriod) {
  const fs::path scratch = scratch_dir("adv_resample");
  std::ofstream(scratch / "op1.csv") << op1_text();
  const RunResult r = run_canalsim("resample op1.csv -o slow.csv --period 0.26", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string text = read_text(scratch / "slow.csv");
  EXPECT_NE(text.find("# sampling_period_s: 0.26\n"), std::string::npos) << text.substr(0, 400);
  const RunResult fit = run_canalsim("fit -m liom slow.csv", scratch);
  EXPECT_EQ(fit.code, 0) << fit.err;
  fs::remove_all(scratch);
}

// An empty value would read as the option not given (a JSON not written, the default grid, the
// current directory) or fail after the work naming nothing; a named FIFO as a recording would
// block for ever; a number the parser cannot convert would say so without the range expected.
TEST(Adversarial, EmptyValuesFifosAndUnconvertibleNumbersAreOneLineBeforeAnyWork) {
  const fs::path scratch = scratch_dir("adv_values");
  std::ofstream(scratch / "op1.csv") << op1_text();
  ASSERT_EQ(::mkfifo((scratch / "fifo.csv").c_str(), 0600), 0);
  const std::vector<ErrorCase> cases = {
      {"fit -m liom op1.csv --json ''", "--json: expected a value, got an empty string"},
      {"resample op1.csv -o '' --period 0.26", "expected a value, got an empty string"},
      {"simulate lab -e op1 --out-dir ''", "--out-dir: expected a value, got an empty string"},
      {"linearize lab -e op1 --freq ''", "--freq: expected a value, got an empty string"},
      {"scenarios --show ''", "--show: expected a value, got an empty string"},
      {"fit -m liom fifo.csv", "fifo.csv: is a FIFO, expected a recording file"},
      {"prbs --stages abc", "--stages: expected a number of stages from 2 to 20, got abc"},
      {"prbs --seed -1", "--seed: expected a seed from 0 to 9007199254740992, got -1"},
      {"prbs --clock 1e-300", "--clock: expected a clock period in s in [1e-06, 3600], got 1e-300"},
      {"prbs --amplitude 1e300", "--amplitude: expected an amplitude in mm in [1e-06, 1000], got 1e300"},
      {"dambreak --cells abc", "--cells: expected a number of cells from 2 to 100000000, got abc"},
      {"blindtest --seed -1 --trials 1", "--seed: expected a seed from 0 to 9007199254740992, got -1"},
      {"reproduce -o /dev", "--out /dev: /dev/tables.json is in /dev"},
  };
  expect_errors(cases, scratch);
  EXPECT_EQ(entry_count(scratch), 2u);  // op1.csv and the FIFO: nothing written
  fs::remove_all(scratch);
}

// Flags and metadata that would change nothing, or change the result without a word, and inputs
// that leave nothing to fit, are refused; a parameter that ends on a bound is said to.
TEST(Adversarial, IgnoredFlagsContradictoryUnitsAndUnexcitedRecordingsAreRefused) {
  const fs::path scratch = scratch_dir("adv_ignored");
  std::ofstream(scratch / "op1.csv") << op1_text();
  std::ofstream(scratch / "scale_only.csv") << with_metadata("# u_scale_mm_per_unit: 2");
  std::ofstream(scratch / "hex.csv") << with_metadata("# operating_opening_mm: 0x10");
  std::string late = "t_s,u_mm,y_up_mm,y_dwe_mm\n";
  for (int k = 0; k < 400; ++k) late += std::to_string(0.13 * k) + "," + (k < 399 ? "15" : "20") + ",60," + std::to_string(44 + 0.01 * k) + "\n";
  std::ofstream(scratch / "late.csv") << late;
  const std::vector<ErrorCase> cases = {
      {"fit -m nliom-f op1.csv --upstream-level 30", "fit --upstream-level 30: every recording has a y_up_mm column"},
      {"diagnose --model liom op1.csv --upstream-level 60", "diagnose --upstream-level 60: model liom does not use"},
      {"fit -m liom op1.csv --memory full", "fit --memory: model liom has no fractional order"},
      {"fit -m liom scale_only.csv", "metadata u_scale_mm_per_unit: 2 mm per unit of no name: expected u_unit too"},
      {"fit -m liom hex.csv", "metadata operating_opening_mm: '0x10': expected a number of mm"},
      {"fit -m liom late.csv", "late.csv: the command first leaves its operating point 15 mm at t = 51.87 s, 1 samples"},
  };
  expect_errors(cases, scratch);
  const RunResult bound = run_canalsim("fit -m liom op1.csv --bounds K=0.001:0.01", scratch);
  EXPECT_EQ(bound.code, 0) << bound.err;
  EXPECT_NE(bound.err.find("canalsim: warning: fit of liom to op1.csv: K = 0.01 is at its upper bound"), std::string::npos)
      << bound.err;
  fs::remove_all(scratch);
}

// Time stamps of 1e8 s keep their 0.13 s step through resample (written with enough digits), and
// a diagnosis prints an unlimited gate speed as ∞, not inf.
TEST(Adversarial, LargeTimesSurviveResampleAndNoInfIsPrinted) {
  const fs::path scratch = scratch_dir("adv_large_times");
  std::ofstream(scratch / "late_clock.csv") << with_rows([](std::vector<std::string>& f, std::size_t) {
    f[0] = std::to_string(1e8 + std::stod(f[0]));
  });
  const RunResult r = run_canalsim("resample late_clock.csv -o r.csv --period 0.26", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const RunResult fit = run_canalsim("fit -m liom r.csv", scratch);
  EXPECT_EQ(fit.code, 0) << fit.err;
  std::ofstream(scratch / "op1.csv") << op1_text();
  const RunResult d = run_canalsim("diagnose --scenario lab op1.csv --candidates gate_rate_limit sensor_offset", scratch);
  EXPECT_EQ(d.code, 0) << d.err;
  EXPECT_FALSE(prints_non_finite(d.out)) << d.out;
  fs::remove_all(scratch);
}

// A canal of one pool behind the lab's head gate whose experiment replays an input file: the
// scenario the next two tests run, with the upstream `kind` line given.
void write_file_driven_canal(const fs::path& file, const std::string& upstream, const std::string& input) {
  std::ofstream(file) << "name = \"file_driven\"\n[upstream]\n" << upstream
                      << "\n[head_gate]\nwidth_m = 0.08\nmax_opening_m = 0.050\nopening_m = 0.025\ncontrolled = true\n"
                         "[[pools]]\nname = \"main\"\nlength_m = 4.5\nbottom_width_m = 0.08\nwall_height_m = 0.25\n"
                         "manning_n = 0.012\ncells = 50\n[downstream]\nkind = \"gate\"\ntail_level_m = 0.040\n"
                         "[downstream.gate]\nwidth_m = 0.08\nmax_opening_m = 0.050\nopening_m = 0.020\n"
                         "[sensors]\nperiod_s = 0.13\nresolution_mm = 0.05\n"
                         "[[experiments]]\nname = \"rec\"\noperating_opening_mm = 15\nduration_s = 30\n"
                         "[experiments.input]\nkind = \"file\"\nfile = \""
                      << input << "\"\n";
}

// An input file's declared units apply as everywhere else (a command logged in cm drives the gate
// as the same command in mm), and one that leaves the gate's range or ends before the experiment
// says so.
TEST(Adversarial, AnInputFilesDeclaredUnitsApplyAndItsGapsAreWarned) {
  const fs::path scratch = scratch_dir("adv_input_units");
  std::string mm = "t_s,u_mm\n", cm = "# u_unit: cm\n# u_scale_mm_per_unit: 10\nt_s,u_mm\n", wide = mm;
  for (int k = 0; k < 200; ++k) {
    const bool high = (k / 16) % 2 == 0;
    const std::string t = std::to_string(0.13 * k);
    mm += t + "," + (high ? "20" : "10") + "\n";
    cm += t + "," + (high ? "2" : "1") + "\n";
    wide += t + "," + (high ? "70" : "10") + "\n";
  }
  std::ofstream(scratch / "mm.csv") << mm;
  std::ofstream(scratch / "cm.csv") << cm;
  std::ofstream(scratch / "wide.csv") << wide;
  const std::string level = "kind = \"level\"\nlevel_m = 0.06";
  write_file_driven_canal(scratch / "mm.toml", level, "mm.csv");
  write_file_driven_canal(scratch / "cm.toml", level, "cm.csv");
  write_file_driven_canal(scratch / "wide.toml", level, "wide.csv");
  ASSERT_EQ(run_canalsim("simulate mm.toml -o mm_out.csv", scratch).code, 0);
  const RunResult in_cm = run_canalsim("simulate cm.toml -o cm_out.csv", scratch);
  ASSERT_EQ(in_cm.code, 0) << in_cm.err;
  const auto rows = [](const std::string& text) { return text.substr(text.find("t_s,")); };
  EXPECT_EQ(rows(read_text(scratch / "cm_out.csv")), rows(read_text(scratch / "mm_out.csv")));
  // 26 s of input for a 30 s experiment, up to 70 mm for a 50 mm gate: two warnings, and the run.
  const RunResult warned = run_canalsim("simulate wide.toml -o wide_out.csv", scratch);
  EXPECT_EQ(warned.code, 0) << warned.err;
  EXPECT_NE(warned.err.find("canalsim: warning: wide.toml: experiment rec: input file"), std::string::npos) << warned.err;
  EXPECT_NE(warned.err.find("u_mm spans 10 .. 70 mm, outside the gate's range [0, 50] mm"), std::string::npos) << warned.err;
  EXPECT_NE(warned.err.find("t_s covers 0 .. 25.87 s of the experiment's 0 .. 30 s"), std::string::npos) << warned.err;
  fs::remove_all(scratch);
}

// `[upstream] kind = "recorded"` takes the upstream level from the experiment's input file: the
// simulated level just upstream of the gate follows the file's y_up_mm (a 2 mm, 10 s sine) to the
// sensor's resolution, where the scenario's own supply would hold it still.
TEST(Adversarial, ARecordedUpstreamIsDrivenByTheInputFilesLevels) {
  const fs::path scratch = scratch_dir("adv_recorded_upstream");
  std::string input = "t_s,u_mm,y_up_mm\n";
  std::vector<double> level;
  for (int k = 0; k < 232; ++k) {
    const double t = 0.13 * k;
    level.push_back(60.0 + 2.0 * std::sin(2.0 * M_PI * t / 10.0));
    input += std::to_string(t) + "," + ((k / 20) % 2 == 0 ? "20" : "10") + "," + std::to_string(level.back()) + "\n";
  }
  std::ofstream(scratch / "input.csv") << input;
  write_file_driven_canal(scratch / "recorded.toml", "kind = \"recorded\"", "input.csv");
  const RunResult r = run_canalsim("simulate recorded.toml -o out.csv", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string out = read_text(scratch / "out.csv");
  std::istringstream rows(out.substr(out.find("t_s,")));
  std::string line;
  std::getline(rows, line);
  ASSERT_EQ(line.rfind("t_s,u_mm,x_up_mm,y_up_mm,", 0), 0u) << line;
  double worst = 0.0, swing = 0.0;
  for (std::size_t k = 0; std::getline(rows, line); ++k) {
    std::vector<std::string> f;
    std::stringstream split(line);
    for (std::string x; std::getline(split, x, ',');) f.push_back(x);
    worst = std::max(worst, std::abs(std::stod(f[3]) - level[k]));
    swing = std::max(swing, std::abs(std::stod(f[3]) - 60.0));
  }
  EXPECT_LE(worst, 0.05);  // the sensor's 0.05 mm resolution
  EXPECT_GT(swing, 1.9);
  // Without the column the scenario cannot be driven: one line naming the file and the column.
  std::ofstream(scratch / "command_only.csv") << "t_s,u_mm\n0,20\n10,10\n20,20\n30,10\n";
  write_file_driven_canal(scratch / "missing.toml", "kind = \"recorded\"", "command_only.csv");
  const RunResult missing = run_canalsim("simulate missing.toml -o m.csv", scratch);
  EXPECT_TRUE(fails_naming(missing, "command_only.csv: missing column y_up_mm"));
  // A level that cannot feed a gate is refused where it is read, naming the row.
  std::string negative = input;
  negative.replace(negative.find(",60.000000\n"), 11, ",-50\n");
  std::ofstream(scratch / "negative.csv") << negative;
  write_file_driven_canal(scratch / "negative.toml", "kind = \"recorded\"", "negative.csv");
  const RunResult below = run_canalsim("simulate negative.toml -o n.csv", scratch);
  EXPECT_TRUE(is_one_error_line(below)) << below.err;
  EXPECT_NE(below.err.find("negative.csv:2: y_up_mm = -50 mm: expected an upstream level in (0, 100000] mm"), std::string::npos)
      << below.err;
  // The scenario's own recording replays through it: the replay drives the gate with its y_up_mm
  // (and starts from the opening the recording rested at, its first command).
  EXPECT_NE(out.find("# operating_opening_mm: 20\n"), std::string::npos);
  const RunResult diagnosis = run_canalsim("diagnose --scenario recorded.toml out.csv --candidates sensor_offset", scratch);
  EXPECT_EQ(diagnosis.code, 0) << diagnosis.err;
  fs::remove_all(scratch);
}

// Scenario inputs whose keys belong to another kind, a PRBS clocked a billion times a second, and
// a name with a NUL in it are refused when the scenario is read, before anything runs.
TEST(Adversarial, ScenarioInputsThatCannotApplyAreRefusedBeforeTheRun) {
  const fs::path scratch = scratch_dir("adv_scenario_inputs");
  std::ofstream(scratch / "u.csv") << "t_s,u_mm\n0,20\n10,10\n20,20\n30,10\n";
  const std::string level = "kind = \"level\"\nlevel_m = 0.06";
  const struct {
    std::string name, input, expected;
  } cases[] = {
      {"file_stages", "kind = \"file\"\nfile = \"u.csv\"\nstages = 5", "stages: does not apply to kind = \"file\" (only to kind = \"prbs\")"},
      {"prbs_file", "kind = \"prbs\"\nfile = \"u.csv\"", "file: does not apply to kind = \"prbs\""},
      {"constant_amplitude", "kind = \"constant\"\namplitude_mm = 5", "amplitude_mm: does not apply to kind = \"constant\""},
      {"fast_clock", "kind = \"prbs\"\nclock_s = 1e-9", "cell updates"},
  };
  for (const auto& c : cases) {
    std::ostringstream toml;
    {
      write_file_driven_canal(scratch / (c.name + ".toml"), level, "u.csv");
      std::string text = read_text(scratch / (c.name + ".toml"));
      text = text.substr(0, text.find("kind = \"file\"\nfile")) + c.input + "\n";
      std::ofstream(scratch / (c.name + ".toml")) << text;
    }
    const RunResult r = run_canalsim("simulate " + c.name + ".toml -o out.csv", scratch);
    EXPECT_TRUE(fails_naming(r, c.expected)) << c.name;
  }
  write_file_driven_canal(scratch / "nul.toml", level, "u.csv");
  std::string text = read_text(scratch / "nul.toml");
  text.replace(text.find("name = \"rec\""), 12, "name = \"e\\u0000x\"");
  std::ofstream(scratch / "nul.toml") << text;
  expect_refused_writing_nothing(scratch, "simulate nul.toml --out-dir od",
                                 "experiments[0].name contains the control character 0", {"out.csv", "od"});
  fs::remove_all(scratch);
}

// Levels that stop varying part-way: the held-out part of the record is constant, so its Nrmse
// (eq. 19, the fit's error over the data's own variation) divides by zero and is not defined.
// The diagnosis says so ("-" in the table, null in the JSON) and judges the candidates on the
// held-out cost instead; it never prints inf or nan.
TEST(Adversarial, ADiagnosisOfLevelsThatStopVaryingLeavesTheUndefinedIndexOut) {
  const fs::path scratch = scratch_dir("adv_constant_levels");
  std::size_t rows = 0;
  (void)with_rows([&](std::vector<std::string>&, std::size_t) { ++rows; });
  std::ofstream(scratch / "flat.csv") << with_rows([&](std::vector<std::string>& f, std::size_t k) {
    if (k > rows / 3) f[kDownstreamLevel] = "50.000";
  });
  const RunResult r = run_canalsim("diagnose --model lfom flat.csv --json flat.json", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(prints_non_finite(r.out)) << r.out;
  const nlohmann::json d = nlohmann::json::parse(read_text(scratch / "flat.json"));
  int judged = 0;
  for (const auto& e : d["effects"]) {
    if (!e.contains("heldout_nrmse_before") || e.value("note", "") != "") continue;
    ++judged;
    EXPECT_TRUE(e["heldout_nrmse_before"].is_null()) << e.dump();
    EXPECT_TRUE(e["nrmse_before"].is_number()) << e.dump();  // the fitted part still varies
  }
  EXPECT_GT(judged, 0) << r.out;
  fs::remove_all(scratch);
}

}  // namespace
