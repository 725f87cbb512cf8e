#include "sweep/sweep.hpp"

#include <exception>
#include <optional>

#include "cluster/distribute.hpp"
#include "core/errors.hpp"
#include "core/progress.hpp"
#include "scenarios/scenario_toml.hpp"
#include "sweep/cases.hpp"
#include "sweep/compute.hpp"
#include "sweep/journal.hpp"
#include "sweep/report.hpp"
#include "sweep/table.hpp"

namespace canalsim::sweep {
namespace {

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& line : lines) text += (text.empty() ? "" : "; ") + line;
  return text;
}

// The root's side of the run: the journal, and the rows it already holds.
std::optional<Journal> open_journal(const SweepFile& sweep, const SweepOptions& options) {
  if (!cluster::is_root()) return std::nullopt;
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) throw InputError(options.out_dir.string() + ": cannot create the sweep's output directory: " + ec.message());
  const std::filesystem::path file = options.out_dir / kJournalFile;
  return options.resume ? Journal::resume(file, sweep) : Journal::start(file, sweep);
}

// Every row by case: the journal's, then the ones computed now.
std::vector<std::string> rows_by_case(const Journal& journal, std::vector<std::string> computed) {
  for (const auto& [index, row] : journal.finished()) computed[index] = row;
  return computed;
}

}  // namespace

Status SweepOptions::validate() const {
  return Validator()
      .require(!out_dir.empty(), "out_dir", "expected a directory for the outputs")
      .require(threads >= 1 && threads <= 64, "threads", threads, "1..64")
      .status();
}

std::string run_case(const SweepFile& sweep, const scenarios::Scenario& base, std::size_t index) {
  const Case c = case_at(sweep, index);
  try {
    const scenarios::Scenario scenario = case_scenario(sweep, c);
    const CaseFigures figures =
        compute_case(scenario, *scenario.find_experiment(sweep.experiments[c.experiment]), base, sweep.compute);
    return ok_row(sweep, c, figures.cells, joined(figures.warnings));
  } catch (const std::exception& e) {
    return failed_row(sweep, c, e.what());
  }
}

SweepOutputs run_sweep(const SweepFile& sweep, const SweepOptions& options) {
  if (const Status s = options.validate(); !s) throw InputError("sweep options: " + s.message());
  std::optional<Journal> journal = open_journal(sweep, options);
  const scenarios::Scenario base = scenarios::parse_scenario(sweep.scenario_text, sweep.scenario_source);

  const std::size_t count = case_count(sweep);
  cluster::DistributeOptions distribute;
  distribute.threads = options.threads;
  std::optional<ProgressCounter> progress;
  if (journal) {
    distribute.skip.assign(count, false);
    for (const auto& [index, row] : journal->finished()) distribute.skip[index] = true;
    progress.emplace(options.progress, count, journal->finished().size());
    distribute.on_result = [&](std::size_t, const std::string& row) {
      journal->append(row);
      progress->finished("cases");
    };
  }
  std::vector<std::string> computed =
      cluster::distribute(count, [&](std::size_t index) { return run_case(sweep, base, index); }, distribute);
  if (!journal) return {};

  SweepOutputs out;
  out.journal = options.out_dir / kJournalFile;
  out.cases = count;
  out.resumed = journal->finished().size();
  const std::vector<std::string> rows = rows_by_case(*journal, std::move(computed));
  std::string table = table_header(sweep);
  for (const auto& row : rows) {
    table += row;
    ++(row_ok(sweep, row) ? out.ok : out.failed);
  }
  out.files = {{options.out_dir / kTableFile, table},
               {options.out_dir / kReportFile, report_html(sweep, rows)},
               {options.out_dir / kSweepCopyFile, sweep.text}};
  return out;
}

void write_sweep_outputs(const SweepOutputs& outputs) {
  write_files_atomically(outputs.files);
  std::error_code ec;
  std::filesystem::remove(outputs.journal, ec);
}

}  // namespace canalsim::sweep
