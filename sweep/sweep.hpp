// Parameter sweeps of a scenario (docs/sweep.md): every case of a sweep file run over the
// processes of an MPI job and the threads of each (cluster/distribute.hpp), one row of figures
// per case, a journal that lets a stopped sweep resume, and the table and report written together
// when the sweep ends.
//
//   const SweepFile file = read_sweep_file("examples/sweep_small.toml");
//   SweepOptions options;
//   options.out_dir = "out";
//   const SweepOutputs outputs = run_sweep(file, options);   // on the root: the files to write
//   write_sweep_outputs(outputs);                            // table.csv, report.html, sweep.toml
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "core/files.hpp"
#include "core/progress.hpp"
#include "core/status.hpp"
#include "scenarios/scenario.hpp"
#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {

// The files of the output directory.
inline constexpr const char* kTableFile = "table.csv";
inline constexpr const char* kJournalFile = "table.partial.csv";
inline constexpr const char* kReportFile = "report.html";
inline constexpr const char* kSweepCopyFile = "sweep.toml";

struct SweepOptions {
  std::filesystem::path out_dir;  // the outputs and the journal; created when missing
  int threads = 1;                // threads computing cases in each process, [1, 64]
  // Go on with the journal in out_dir: its cases are not run again. Without it an existing
  // journal is an error (the sweep it belongs to is unfinished).
  bool resume = false;
  // On the root, once per finished case: the share of cases done and "case 12/48".
  ProgressCallback progress;

  [[nodiscard]] Status validate() const;
};

struct SweepOutputs {
  std::vector<FileContents> files;  // table.csv, report.html, sweep.toml in out_dir
  std::filesystem::path journal;
  std::size_t cases = 0, ok = 0, failed = 0;
  std::size_t resumed = 0;          // cases read from the journal
};

// The row one case adds to the table: its scenario built and run, its figures computed. A case
// that fails — no steady state, a run or fit refused as too long, a fit or diagnosis error — is
// a row with status "failed" and its error, not an exception. `base` is the parsed base scenario.
std::string run_case(const SweepFile& sweep, const scenarios::Scenario& base, std::size_t index);

// Runs every case not in the journal, the root appending each row to the journal as the case
// finishes. Returns on the root the outputs to write (the table's rows sorted by case); on the
// other processes of an MPI job nothing. Throws InputError before any case runs when the options
// are invalid or the journal is refused (Journal::start, Journal::resume).
SweepOutputs run_sweep(const SweepFile& sweep, const SweepOptions& options);

// Writes the outputs together, all or nothing (write_files_atomically: an existing table.csv
// survives a failure), then removes the journal.
void write_sweep_outputs(const SweepOutputs& outputs);

}  // namespace canalsim::sweep
