// `canalsim sweep FILE.toml --out DIR [--threads N] [--resume]`: every case of a sweep file (a
// base scenario, keys varied over grids or drawn from distributions, experiments, what to compute)
// run and tabulated in DIR/table.csv with a report (docs/sweep.md). Under `mpirun -n N` the cases
// are spread over N processes; only the first (the root) writes and prints.
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "cli/checks.hpp"
#include "cli/commands.hpp"
#include "cluster/distribute.hpp"
#include "core/progress.hpp"
#include "sweep/sweep.hpp"

namespace canalsim::cli {
namespace {

struct SweepArguments {
  std::string file;
  std::string out;
  int threads = 1;
  bool resume = false;
};

// DIR can be made and its files written, and none of them is the sweep file or its scenario.
void check_output_directory(const SweepArguments& args, const sweep::SweepFile& file) {
  check_creatable_directory("--out", args.out);
  std::error_code ec;
  if (!std::filesystem::is_directory(args.out, ec)) return;  // a directory to create holds no input
  const std::filesystem::path dir(args.out);
  std::vector<NamedFile> outputs;
  for (const char* name : {sweep::kTableFile, sweep::kReportFile, sweep::kSweepCopyFile, sweep::kJournalFile}) {
    outputs.push_back({"--out", (dir / name).string()});
  }
  std::vector<NamedFile> inputs = {{"sweep file", args.file}};
  if (file.scenario_source.rfind("builtin:", 0) != 0) inputs.push_back({"scenario file", file.scenario_source});
  check_outputs(outputs, inputs);
}

void run(const SweepArguments& args) {
  // Everything is checked before the first case: the file, the scenario keys, the outputs and (in
  // run_sweep) the journal.
  const sweep::SweepFile file = sweep::read_sweep_file(args.file);
  if (cluster::is_root()) check_output_directory(args, file);
  std::optional<ProgressLine> progress;
  sweep::SweepOptions options;
  options.out_dir = args.out;
  options.threads = args.threads;
  options.resume = args.resume;
  if (cluster::is_root()) {
    progress.emplace("sweep " + args.file);
    options.progress = progress->callback();
  }
  const sweep::SweepOutputs outputs = sweep::run_sweep(file, options);
  if (!cluster::is_root()) return;
  progress->finish();
  sweep::write_sweep_outputs(outputs);
  std::cout << "wrote " << (options.out_dir / sweep::kTableFile).string() << " (" << outputs.cases << " cases: "
            << outputs.ok << " ok, " << outputs.failed << " failed"
            << (outputs.resumed ? ", " + std::to_string(outputs.resumed) + " from the journal" : std::string()) << "), "
            << (options.out_dir / sweep::kReportFile).string() << " and " << (options.out_dir / sweep::kSweepCopyFile).string()
            << "\n";
}

}  // namespace

void add_sweep_command(CLI::App& app) {
  auto args = std::make_shared<SweepArguments>();
  auto* cmd = app.add_subcommand("sweep", "Run a scenario over grids and draws of its keys, one table row per case (docs/sweep.md)");
  cmd->add_option("file", args->file, "Sweep file (TOML): base scenario, [[vary]] keys, experiments, [compute]")->required();
  cmd->add_option("--out", args->out, "Directory for table.csv, report.html and sweep.toml (created if missing)")->required();
  cmd->add_option("--threads", args->threads, "Threads computing cases in each process (default 1)")->check(thread_count());
  cmd->add_flag("--resume", args->resume,
                "Complete the sweep whose journal (table.partial.csv) is in --out: its finished cases are not run again");
  cmd->callback([args] { run(*args); });
}

}  // namespace canalsim::cli
