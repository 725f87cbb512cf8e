// `canalsim diagnose --scenario S REC.csv... [--json F] [--report F.html]`: replays each
// recording's gate command through the scenario, locates where model and recordings disagree,
// names the missing physics from the catalog, refits it and shows the fit improve
// (docs/diagnosis.md). Prints a summary; the JSON and HTML are written atomically and only when
// the whole diagnosis succeeded.
#include <fstream>
#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "cli/progress.hpp"
#include "diagnosis/diagnose.hpp"
#include "diagnosis/report.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/recording.hpp"

namespace canalsim::cli {
namespace {

struct DiagnoseArguments {
  std::string scenario;
  std::vector<std::string> recordings;
  std::string json;
  std::string report;
  std::vector<std::string> candidates;
  double fit_fraction = 0.5;
  int threads = 2;
  bool recorded_upstream = false;
  bool no_clock = false;
};

int run(const DiagnoseArguments& args) {
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
  // Read every recording first and report all that fail, so the user fixes them in one go.
  std::vector<Recording> recordings;
  std::string problems;
  for (const auto& file : args.recordings) {
    try {
      recordings.push_back(read_recording(file));
    } catch (const InputError& e) {
      problems += std::string(problems.empty() ? "" : "\n") + e.what();
    }
  }
  for (const auto& p : diagnosis::check_recordings(s, recordings)) {
    problems += std::string(problems.empty() ? "" : "\n") + p;
  }
  if (!problems.empty()) throw InputError("recordings do not match scenario " + s.name + ":\n" + problems);

  diagnosis::DiagnoseOptions options;
  options.candidates = args.candidates;
  options.fit_fraction = args.fit_fraction;
  options.threads = args.threads;
  options.use_recorded_upstream = args.recorded_upstream;
  options.reconstruct_clock = !args.no_clock;
  Progress progress("diagnosing " + std::to_string(recordings.size()) + " recording(s) against " + s.name);
  options.progress = [&progress](double f, const std::string&) { progress.update(f); };
  const diagnosis::Diagnosis d = diagnosis::diagnose(s, recordings, options);
  progress.finish();
  std::cout << diagnosis::text_summary(d);
  if (!d.ok) {
    std::cerr << "canalsim: error: diagnosis failed: " << d.message << '\n';
    return 1;
  }
  if (!args.json.empty()) {
    write_file_atomically(args.json, diagnosis::to_json(d).dump(2) + "\n");
    std::cout << "wrote " << args.json << '\n';
  }
  if (!args.report.empty()) {
    write_file_atomically(args.report, diagnosis::html_report(d, "canalsim diagnosis: " + s.name));
    std::cout << "wrote " << args.report << '\n';
  }
  return 0;
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto args = std::make_shared<DiagnoseArguments>();
  auto* cmd = app.add_subcommand("diagnose", "Locate and explain the mismatch between a scenario and recordings");
  cmd->add_option("--scenario", args->scenario, "Built-in scenario name or TOML file")->required();
  cmd->add_option("recordings", args->recordings, "Recording CSV files")->required();
  cmd->add_option("--json", args->json, "Write the diagnosis as JSON");
  cmd->add_option("--report", args->report, "Write a self-contained HTML report");
  cmd->add_option("--candidates", args->candidates, "Catalog effects to try (default: all)");
  cmd->add_option("--fit-fraction", args->fit_fraction, "Leading share of each recording used for fitting (default 0.5)")
      ->check(CLI::Range(0.11, 0.89));
  cmd->add_option("--threads", args->threads, "Recordings simulated in parallel (default 2)")->check(CLI::Range(1, 64));
  cmd->add_flag("--recorded-upstream", args->recorded_upstream,
                "Drive the head gate with the recorded y_up_mm instead of the scenario's upstream model");
  cmd->add_flag("--no-clock", args->no_clock,
                "Replay the sampled command as sampled (no reconstruction of a PRBS clock)");
  cmd->callback([args] {
    const int code = run(*args);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace canalsim::cli
