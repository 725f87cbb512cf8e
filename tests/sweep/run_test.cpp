// A real sweep through the library: its rows equal what the simulator, the fit and the
// linearisation give when called directly; a case that fails is a row with its error; a journal
// cut after k rows is completed into the table an uninterrupted run writes, byte for byte. The
// lab canal on 30 cells over 20 s keeps each case well under a second.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "core/errors.hpp"
#include "linearize/linearize.hpp"
#include "reduced_models/identification.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"
#include "sweep/cases.hpp"
#include "sweep/journal.hpp"
#include "sweep/sweep.hpp"
#include "sweep/table.hpp"

namespace canalsim::sweep {
namespace {

namespace fs = std::filesystem;

const char* kSmallSweep = R"(# two pool lengths, and a grid too fine to run
scenario = "lab"
experiments = ["op1"]
duration_s = 20
[[vary]]
key = "pools[1].cells"
values = [30, 1000000]
[[vary]]
key = "pools[1].length_m"
values = [4.0, 5.0]
[compute]
fit = ["LFOM"]
linearize = true
)";

// A directory of its own for one test, removed after it.
struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() / ("canalsim_sweep_test_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() { fs::remove_all(dir); }
};

SweepFile small_sweep() { return parse_sweep_file(kSmallSweep, "small.toml", "."); }

std::string read(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> table_rows(const std::string& table) {
  std::vector<std::string> rows;
  std::istringstream in(table);
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) rows.push_back(line + "\n");
  return rows;
}

double cell(const SweepFile& f, const std::string& row, const std::string& column) {
  const auto columns = table_columns(f);
  const auto at = std::find(columns.begin(), columns.end(), column);
  EXPECT_NE(at, columns.end()) << column;
  return std::strtod(split_csv_line(row)[static_cast<std::size_t>(at - columns.begin())].c_str(), nullptr);
}

// The uninterrupted run, once for the suite.
const std::string& uninterrupted_table() {
  static const std::string table = [] {
    Scratch scratch("uninterrupted");
    SweepOptions options;
    options.out_dir = scratch.dir / "out";
    const SweepOutputs outputs = run_sweep(small_sweep(), options);
    EXPECT_EQ(outputs.cases, 4u);
    EXPECT_EQ(outputs.ok, 2u);
    EXPECT_EQ(outputs.failed, 2u);
    EXPECT_EQ(outputs.resumed, 0u);
    EXPECT_TRUE(fs::exists(scratch.dir / "out" / kJournalFile)) << "the journal is kept until the table is written";
    write_sweep_outputs(outputs);
    EXPECT_FALSE(fs::exists(scratch.dir / "out" / kJournalFile));
    EXPECT_EQ(read(scratch.dir / "out" / kSweepCopyFile), kSmallSweep);
    const std::string report = read(scratch.dir / "out" / kReportFile);
    EXPECT_NE(report.find("2 ok, 2 failed"), std::string::npos);
    EXPECT_NE(report.find("<svg"), std::string::npos);
    return read(scratch.dir / "out" / kTableFile);
  }();
  return table;
}

TEST(SweepRun, AnOkRowHoldsWhatTheLibrariesComputeForItsCaseDirectly) {
  const SweepFile f = small_sweep();
  const std::vector<std::string> rows = table_rows(uninterrupted_table());
  ASSERT_EQ(rows.size(), 4u);
  const std::string& row = rows[1];  // 30 cells, 5 m
  ASSERT_TRUE(row_ok(f, row)) << row;
  EXPECT_EQ(cell(f, row, "pools[1].length_m"), 5.0);

  // The same canal built from the scenario value by value, not from the sweep's edited text.
  scenarios::Scenario s = scenarios::builtin_scenario("lab");
  s.pools.front().cells = 30;
  s.pools.front().length_m = 5.0;
  scenarios::ExperimentSpec e = *s.find_experiment("op1");
  e.duration_s = 20.0;
  scenarios::SimulateOptions run;
  run.require_steady_state = true;
  const Recording recording = scenarios::simulate(s, e, run);
  reduced::FitOptions fit_options;
  fit_options.criterion = reduced::Criterion::least_squares;
  const reduced::FitResult fit = reduced::fit(reduced::ModelKind::lfom, reduced::prepare_data(recording), fit_options);
  EXPECT_EQ(cell(f, row, "LFOM_lambda"), fit.model.p.lambda);
  EXPECT_EQ(cell(f, row, "LFOM_K_mm_per_mm"), fit.model.p.K);
  EXPECT_EQ(cell(f, row, "LFOM_L_s"), fit.model.p.L);
  EXPECT_EQ(cell(f, row, "LFOM_lambda_std"), fit.std[2]);
  EXPECT_EQ(cell(f, row, "LFOM_nrmse_pct"), fit.nrmse.front());
  const auto& y = recording.column("y_dwe_mm");
  EXPECT_EQ(cell(f, row, "y_dwe_max_mm"), *std::max_element(y.begin(), y.end()));

  const linearize::FrequencyResponse pool = linearize::linearize(s, e, {});
  ASSERT_TRUE(pool.band_fit);
  EXPECT_EQ(cell(f, row, "lin_lambda"), pool.band_fit->order);
  EXPECT_EQ(cell(f, row, "lin_static_gain_mm_per_mm"), pool.static_gain);
  EXPECT_GT(cell(f, row, "lin_lambda"), 0.1);
}

TEST(SweepRun, ACaseThatFailsIsARowWithItsError) {
  const SweepFile f = small_sweep();
  const std::vector<std::string> rows = table_rows(uninterrupted_table());
  const std::string& failed = rows[2];  // a million cells: refused by the run's cost guard
  EXPECT_FALSE(row_ok(f, failed));
  const std::vector<std::string> cells = split_csv_line(failed);
  EXPECT_EQ(cells[0], "2");
  EXPECT_EQ(cells[3], "1000000");
  EXPECT_EQ(cells[5], "failed");
  EXPECT_NE(cells[6].find("cell updates"), std::string::npos) << cells[6];
  for (std::size_t c = 7; c < cells.size(); ++c) EXPECT_EQ(cells[c], "") << "no figure for a failed case";
  EXPECT_EQ(cells.size(), table_columns(f).size());
}

TEST(SweepRun, AJournalCutAfterSomeRowsIsCompletedIntoTheSameTableByteForByte) {
  const SweepFile f = small_sweep();
  const std::vector<std::string> rows = table_rows(uninterrupted_table());
  Scratch scratch("resume");
  const fs::path out = scratch.dir / "out";
  fs::create_directories(out);
  {
    // Two cases finished, in the order they finished, and a third cut short as it was written.
    Journal journal = Journal::start(out / kJournalFile, f);
    journal.append(rows[3]);
    journal.append(rows[0]);
    journal.append(rows[1].substr(0, rows[1].size() / 2));
  }
  SweepOptions options;
  options.out_dir = out;
  options.threads = 2;
  options.resume = true;
  int reports = 0;
  options.progress = [&reports](const ProgressReport& r) {
    ++reports;
    EXPECT_EQ(r.message, std::to_string(2 + reports) + "/4 cases");
  };
  const SweepOutputs outputs = run_sweep(f, options);
  EXPECT_EQ(outputs.resumed, 2u);
  EXPECT_EQ(reports, 2) << "one report per case computed now";
  write_sweep_outputs(outputs);
  EXPECT_EQ(read(out / kTableFile), uninterrupted_table());
  EXPECT_FALSE(fs::exists(out / kJournalFile));
}

TEST(SweepRun, AJournalIsRefusedWithoutResumeAndWhenItIsAnotherSweeps) {
  const SweepFile f = small_sweep();
  Scratch scratch("refused");
  const fs::path out = scratch.dir / "out";
  fs::create_directories(out);
  { Journal::start(out / kJournalFile, f); }
  SweepOptions options;
  options.out_dir = out;
  try {
    run_sweep(f, options);
    ADD_FAILURE() << "an unfinished sweep's journal was overwritten";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expected --resume"), std::string::npos) << e.what();
  }
  std::string other_text = kSmallSweep;
  other_text.replace(other_text.find("4.0"), 3, "4.5");
  const SweepFile other = parse_sweep_file(other_text, "other.toml", ".");
  options.resume = true;
  try {
    run_sweep(other, options);
    ADD_FAILURE() << "another sweep's journal was resumed";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("the journal of another sweep file"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(out / kTableFile));
}

}  // namespace
}  // namespace canalsim::sweep
