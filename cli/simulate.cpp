// `canalsim simulate SCENARIO [--experiment NAME] [-o FILE | --out-dir DIR]`: runs experiments of
// a scenario (a built-in name or a TOML file) and writes their recordings
// (docs/recording-format.md).
#include <filesystem>
#include <iostream>

#include "cli/commands.hpp"
#include "cli/progress.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/recording.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::cli {
namespace {

struct SimulateArguments {
  std::string scenario;
  std::vector<std::string> experiments;
  std::string output;
  std::string out_dir = ".";
};

std::string safe_file_name(std::string name) {
  for (char& c : name) {
    if (c == '*') c = 's';  // op1* -> op1s
    if (c == '/' || c == ' ') c = '_';
  }
  return name;
}

void run(const SimulateArguments& args) {
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
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
  if (!args.output.empty() && chosen.size() != 1) {
    throw InputError("-o writes one recording: choose one experiment with --experiment, or use --out-dir");
  }
  if (args.output.empty() && !std::filesystem::is_directory(args.out_dir)) {
    throw InputError(args.out_dir + ": --out-dir is not an existing directory");
  }
  for (const auto* e : chosen) {
    scenarios::SimulateOptions options;
    Progress progress("simulating " + s.name + "/" + e->name);
    options.progress = [&progress](double f) { progress.update(f); };
    const Recording rec = scenarios::simulate(s, *e, options);
    progress.finish();
    const std::filesystem::path file =
        args.output.empty() ? std::filesystem::path(args.out_dir) / (safe_file_name(e->name) + ".csv")
                            : std::filesystem::path(args.output);
    write_recording(file, rec);
    std::cout << "wrote " << file.string() << " (" << rec.size() << " samples, "
              << rec.sample_period() << " s)\n";
  }
}

}  // namespace

void add_simulate_command(CLI::App& app) {
  auto args = std::make_shared<SimulateArguments>();
  auto* cmd = app.add_subcommand("simulate", "Run experiments of a scenario and write recordings (CSV)");
  cmd->add_option("scenario", args->scenario, "Built-in scenario name (see `canalsim scenarios`) or TOML file")->required();
  cmd->add_option("--experiment,-e", args->experiments, "Experiment(s) to run (default: all)");
  cmd->add_option("-o,--output", args->output, "Recording file for a single experiment");
  cmd->add_option("--out-dir", args->out_dir, "Directory for the recordings, one NAME.csv each (default: .)");
  cmd->callback([args] { run(*args); });
}

}  // namespace canalsim::cli
