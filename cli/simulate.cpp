// `canalsim simulate SCENARIO [--experiment NAME] [-o FILE | --out-dir DIR]`: runs experiments of
// a scenario (a built-in name or a TOML file) and writes their recordings
// (docs/recording-format.md).
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "cli/checks.hpp"
#include "cli/commands.hpp"
#include "scenarios/builtin.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"
#include "scenarios/run_report.hpp"
#include "scenarios/simulate.hpp"
#include "scenarios/staggered.hpp"

namespace canalsim::cli {
namespace {

struct SimulateArguments {
  std::string scenario;
  std::vector<std::string> experiments;
  std::string output;
  std::string out_dir;  // empty: not given (the current directory, unless -o)
  bool allow_long = false;
  std::string scheme = "finite-volume";  // or "staggered": the second simulator
  int staggered_cells = scenarios::StaggeredOptions{}.cells;
};

// The recording file name of an experiment under --out-dir (docs/recording-format.md): `*` reads
// as "star" in the paper's names (op1*), '/' and ' ' would make a path or need quoting.
std::string safe_file_name(std::string name) {
  for (char& c : name) {
    if (c == '*') c = 's';  // op1* -> op1s
    if (c == '/' || c == ' ') c = '_';
  }
  return name;
}

std::vector<const scenarios::ExperimentSpec*> choose_experiments(const scenarios::Scenario& s,
                                                                  const SimulateArguments& args) {
  std::vector<const scenarios::ExperimentSpec*> chosen;
  for (const auto& name : args.experiments) {
    const auto* e = s.find_experiment(name);
    if (!e) {
      std::string names;
      for (const auto& x : s.experiments) names += (names.empty() ? "" : ", ") + x.name;
      throw InputError(args.scenario + ": no experiment '" + name + "' (experiments: " + names + ")");
    }
    chosen.push_back(e);
  }
  if (chosen.empty()) {
    for (const auto& e : s.experiments) chosen.push_back(&e);
  }
  if (chosen.empty()) throw InputError(args.scenario + ": the scenario has no [[experiments]]");
  return chosen;
}

// One file per experiment under --out-dir. Two experiments mapping to the same file (op1* and
// op1s both -> op1s.csv) would silently overwrite each other, so that is refused before any
// simulation runs.
std::vector<std::filesystem::path> output_files(const std::vector<const scenarios::ExperimentSpec*>& chosen,
                                                const SimulateArguments& args) {
  if (!args.output.empty()) return {std::filesystem::path(args.output)};
  const std::filesystem::path dir = args.out_dir.empty() ? "." : args.out_dir;
  std::map<std::string, std::string> owner;  // file name -> experiment
  std::vector<std::filesystem::path> files;
  for (const auto* e : chosen) {
    const std::string file = safe_file_name(e->name) + ".csv";
    const auto [it, fresh] = owner.emplace(file, e->name);
    if (!fresh && it->second == e->name) throw InputError("--experiment " + e->name + ": given twice");
    if (!fresh) {
      throw InputError("--out-dir: experiments '" + it->second + "' and '" + e->name + "' would both be written to " +
                       (dir / file).string() + "; run them separately with -e NAME -o FILE");
    }
    files.push_back(dir / file);
  }
  return files;
}

// Every argument problem is reported before the first (possibly long) simulation starts.
void check_outputs(const std::vector<const scenarios::ExperimentSpec*>& chosen, const SimulateArguments& args) {
  if (!args.output.empty() && !args.out_dir.empty()) {
    throw InputError("-o " + args.output + " and --out-dir " + args.out_dir +
                     ": give one (-o writes one recording, --out-dir one per experiment)");
  }
  if (!args.output.empty() && chosen.size() != 1) {
    throw InputError("-o writes one recording: choose one experiment with --experiment, or use --out-dir");
  }
  if (!args.output.empty()) check_output_file("-o", args.output);
  if (!args.out_dir.empty()) check_creatable_directory("--out-dir", args.out_dir);
}

Recording run_finite_volume(const scenarios::Scenario& s, const scenarios::ExperimentSpec& e, const SimulateArguments& args) {
  scenarios::SimulateOptions options;
  options.allow_long_run = args.allow_long;
  ProgressLine progress("simulating " + s.name + "/" + e.name);
  options.progress = progress.callback();
  Recording rec = scenarios::simulate(s, e, options);
  progress.finish();
  return rec;
}

// The second simulator (scenarios/staggered.hpp) runs a 255.5 s experiment in a fraction of a
// second on 300 cells: no progress line.
Recording run_staggered(const scenarios::Scenario& s, const scenarios::ExperimentSpec& e, const SimulateArguments& args) {
  scenarios::StaggeredOptions options;
  options.cells = args.staggered_cells;
  return scenarios::simulate_staggered(s, e, options);
}

void run(const SimulateArguments& args) {
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
  const auto chosen = choose_experiments(s, args);
  check_outputs(chosen, args);
  const auto files = output_files(chosen, args);
  std::vector<NamedFile> outputs_named, inputs{{"scenario", args.scenario}};
  for (const auto& f : files) outputs_named.push_back({args.output.empty() ? "--out-dir" : "-o", f.string()});
  for (const auto* e : chosen) {
    if (e->input.kind == scenarios::InputKind::file) inputs.push_back({"input file of " + e->name, e->input.file});
  }
  // A directory --out-dir creates holds neither an input nor a file to replace.
  std::error_code ec;
  if (!args.output.empty() || std::filesystem::is_directory(args.out_dir.empty() ? "." : args.out_dir, ec)) {
    check_outputs(outputs_named, inputs);
  }
  // Every experiment runs first; the recordings are written together at the end, all or nothing,
  // so that a failure in the third experiment leaves no first two files (and replaces nothing).
  std::vector<FileContents> outputs;
  std::vector<std::string> summaries;
  for (std::size_t i = 0; i < chosen.size(); ++i) {
    const auto* e = chosen[i];
    const Recording rec = args.scheme == "staggered" ? run_staggered(s, *e, args) : run_finite_volume(s, *e, args);
    for (const auto& line : scenarios::run_report_lines(rec)) std::cerr << "canalsim: " << line << '\n';
    outputs.emplace_back(files[i], format_recording(rec));
    summaries.push_back("wrote " + files[i].string() + " (" + std::to_string(rec.size()) + " samples, " +
                        format_g(rec.sample_period()) + " s)");
  }
  // Created only now, so that a run that fails in a simulation leaves no directory.
  if (!args.out_dir.empty()) create_directory_for("--out-dir", args.out_dir);
  write_files_atomically(outputs);
  for (const auto& line : summaries) std::cout << line << '\n';
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArguments>();
  auto* cmd = app.add_subcommand("simulate", "Run experiments of a scenario and write recordings (CSV)");
  cmd->add_option("scenario", args->scenario, "Built-in scenario name (see `canalsim scenarios`) or TOML file")->required();
  cmd->add_option("--experiment,-e", args->experiments, "Experiment(s) to run (default: all)");
  cmd->add_option("-o,--output", args->output, "Recording file for a single experiment (not with --out-dir)");
  cmd->add_option("--out-dir", args->out_dir,
                  "Directory for the recordings, created if missing; one NAME.csv each, '*' in NAME written "
                  "as 's' (op1* -> op1s.csv) (default: .)");
  cmd->add_flag("--allow-long", args->allow_long,
                "Run past the cost ceilings (3e10 cell updates, 2 GB; docs/scenarios.md, \"Run cost\")");
  cmd->add_option("--scheme", args->scheme,
                  "finite-volume: canalsim's model; staggered: a second simulator written apart from it (another scheme "
                  "and gate-law regularisation; one rectangular pool; docs/numerics.md), a truth to test fits against")
      ->check(CLI::IsMember({"finite-volume", "staggered"}))
      ->capture_default_str();
  cmd->add_option("--staggered-cells", args->staggered_cells, "Cells of the staggered simulator's pool")
      ->check(CLI::Range(3, 100000))
      ->capture_default_str();
  cmd->callback([args] { run(*args); });
}

}  // namespace canalsim::cli
