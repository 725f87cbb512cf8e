// `canalsim diagnose --scenario S REC.csv... [--json F] [--report F.html] [--plots-dir DIR]`: replays each
// recording's gate command through the scenario, locates where model and recordings disagree,
// names the missing physics from the catalog, refits it and shows the fit improve
// (docs/diagnosis.md). With `--baseline BASE.csv... --` the scenario is first calibrated on the
// baseline recordings and the recordings are diagnosed against the calibrated scenario
// (diagnosis/baseline.hpp). `canalsim diagnose --model M REC.csv...` does the same for a reduced model
// (diagnosis/model_diagnosis.hpp). Prints a summary; the JSON and HTML are written atomically and only when
// the whole diagnosis succeeded.
#include <algorithm>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "cli/checks.hpp"
#include "cli/recording_format.hpp"
#include "cli/finite_figures.hpp"
#include "cli/commands.hpp"
#include "core/declared_units.hpp"
#include "diagnosis/baseline.hpp"
#include "diagnosis/diagnose.hpp"
#include "diagnosis/model_diagnosis.hpp"
#include "reduced_models/models.hpp"
#include "diagnosis/report.hpp"
#include "cli/plots_dir.hpp"
#include "scenarios/builtin.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"
#include "scenarios/run_cost.hpp"

namespace canalsim::cli {
namespace {

struct DiagnoseArguments {
  std::string scenario;
  std::string model;
  double quantum_mm = 0.0;
  double gate_speed_mm_s = 0.0;
  std::optional<double> upstream_level_mm;
  std::vector<std::string> recordings;
  std::vector<std::string> baseline;
  std::string json;
  std::string report;
  PlotsDirectory plots;
  std::vector<std::string> candidates;
  double fit_fraction = 0.5;
  int threads = 2;
  bool recorded_upstream = false;
  bool no_clock = false;
  bool allow_long = false;
  int search_cells = diagnosis::DiagnoseOptions{}.search_max_cells;
  std::vector<std::string> flags_given;  // the flags the user typed, for check_flags_apply
  RecordingFormat format;
};

// Stops at the first unreadable recording: its error names the file and line, and the next
// file's problem (or a "no recordings" that only follows from the first) would be noise.
std::vector<Recording> read_all(const std::vector<std::string>& files, const RecordingFormat& format) {
  std::vector<Recording> recordings;
  for (const auto& file : files) recordings.push_back(format.read(file));
  return recordings;
}

// For a scenario, in millimetres: a command or levels logged in other units (# u_unit,
// # u_scale_mm_per_unit; docs/recording-format.md) are converted here, so every check sees mm.
// (A reduced model keeps the declared units: it reports its gain in them.)
std::vector<Recording> read_all_in_mm(const std::vector<std::string>& files, const RecordingFormat& format) {
  std::vector<Recording> recordings = read_all(files, format);
  for (Recording& r : recordings) r = in_millimetres(std::move(r));
  return recordings;
}

// --recorded-upstream drives the head gate with each recording's y_up_mm: every one must have it.
void check_recorded_upstream(const std::vector<Recording>& recordings, const DiagnoseArguments& args) {
  if (!args.recorded_upstream) return;
  for (const Recording& r : recordings) {
    if (!r.has(columns::upstream_level)) {
      throw InputError(r.source + ": missing column y_up_mm: --recorded-upstream drives the head gate with it");
    }
  }
}

// Outputs are written at the end of a diagnosis that can take minutes: check their places first.
void check_diagnosis_outputs(const DiagnoseArguments& args) {
  std::vector<NamedFile> inputs = named_files("recording", args.recordings);
  for (const NamedFile& b : named_files("--baseline recording", args.baseline)) inputs.push_back(b);
  if (!args.scenario.empty()) inputs.push_back({"--scenario", args.scenario});
  check_outputs({{"--json", args.json}, {"--report", args.report}}, inputs);
  args.plots.check();
}

// The JSON, the HTML report and the plots are written together, all or nothing: a report that
// cannot be written leaves no JSON behind either (and replaces neither).
int write_outputs(const diagnosis::Diagnosis& d, const DiagnoseArguments& args, const std::string& title,
                  const nlohmann::json& baseline = nullptr) {
  nlohmann::json json = diagnosis::to_json(d);
  if (!baseline.is_null()) json["baseline"] = baseline;
  if (d.ok) require_finite_figures(json, "diagnosis");
  std::cout << diagnosis::text_summary(d);
  if (!d.ok) {
    std::cerr << "canalsim: error: diagnosis failed: " << d.message << '\n';
    return 1;
  }
  std::vector<FileContents> outputs;
  if (!args.json.empty()) outputs.emplace_back(args.json, json.dump(2) + "\n");
  if (!args.report.empty()) outputs.emplace_back(args.report, diagnosis::html_report(d, title));
  outputs = args.plots.write(std::move(outputs), args.plots.dir.empty() ? std::vector<plot::Figure>{} : diagnosis::report_figures(d));
  for (const auto& [file, text] : outputs) std::cout << "wrote " << file.string() << '\n';
  return 0;
}

int run_model(const DiagnoseArguments& args) {
  const std::vector<Recording> recordings = read_all(args.recordings, args.format);
  diagnosis::ModelDiagnoseOptions options;
  options.kind = reduced::require_model_kind(args.model);
  // --upstream-level stands in for a missing y_up_mm column of a model that uses the level.
  if (args.upstream_level_mm) {
    const std::string flag = "diagnose --upstream-level " + format_g(*args.upstream_level_mm);
    if (!reduced::uses_upstream_level(options.kind)) {
      throw InputError(flag + ": model " + args.model +
                       " does not use the upstream level (nliom-f, nlfom-f, nliom-s, nlfom-s and hybrid do)");
    }
    if (std::all_of(recordings.begin(), recordings.end(), [](const Recording& r) { return r.has(columns::upstream_level); })) {
      throw InputError(flag + ": every recording has a y_up_mm column, which is used instead (the flag is for recordings without one)");
    }
  }
  options.candidates = args.candidates;
  options.fit_fraction = args.fit_fraction;
  options.quantum_mm = args.quantum_mm;
  options.gate_speed_mm_s = args.gate_speed_mm_s;
  options.data.upstream_level_mm = args.upstream_level_mm;
  ProgressLine progress("diagnosing " + std::to_string(recordings.size()) + " recording(s) against " + args.model);
  options.progress = progress.callback();
  const diagnosis::Diagnosis d = diagnosis::diagnose_model(recordings, options);
  progress.finish();
  return write_outputs(d, args, "canalsim diagnosis: " + args.model);
}

// A diagnosis replays every recording through the scenario about 1 + 5 times per candidate
// effect (the progress budget of diagnosis::diagnose): its cost is that many runs of the
// recording's length (scenarios/run_cost.hpp), refused above one run's ceiling on each thread
// the replays keep busy.
void check_diagnosis_cost(const scenarios::Scenario& s, const std::vector<Recording>& recordings,
                          const std::vector<Recording>& baseline, const DiagnoseArguments& args) {
  if (args.allow_long) return;
  const std::size_t parallel = std::max(recordings.size(), baseline.size());
  const double ceiling = scenarios::replays_ceiling(args.threads, parallel);
  const std::string expected = "expected at most " + scenarios::replays_ceiling_text(args.threads, parallel);
  const double candidates = args.candidates.empty() ? 10.0 : static_cast<double>(args.candidates.size());
  double updates = 0.0;
  for (const Recording& rec : recordings) {
    updates += (1.0 + 5.0 * candidates) * scenarios::estimate_replay_cost(s, rec).cell_updates;
  }
  // A calibration on a baseline replays each baseline recording about 100–150 times (30
  // Levenberg–Marquardt iterations with a finite-difference Jacobian; bench/README.md).
  for (const Recording& rec : baseline) {
    const double cost = 100.0 * scenarios::estimate_replay_cost(s, rec).cell_updates;
    if (updates + cost > ceiling) {
      throw InputError("diagnose: calibrating on the baseline replays " + rec.source + " (" + format_g(rec.size(), 3) +
                       " samples) about 100 times through " + s.name + ": with the diagnosis about " +
                       format_g(updates + cost, 3) + " cell updates, " + expected +
                       " (shorter recordings; or pass --allow-long)");
    }
    updates += cost;
  }
  if (updates > ceiling) {
    throw InputError("diagnose: replaying " + std::to_string(recordings.size()) + " recording(s) of " +
                     format_g(recordings.front().size(), 3) + "+ samples about " + format_g(1.0 + 5.0 * candidates) +
                     " times each through " + s.name + " is about " + format_g(updates, 3) + " cell updates, " +
                     expected + " (shorter recordings, fewer --candidates; or pass --allow-long)");
  }
}

diagnosis::DiagnoseOptions diagnose_options(const DiagnoseArguments& args) {
  diagnosis::DiagnoseOptions options;
  options.candidates = args.candidates;
  options.fit_fraction = args.fit_fraction;
  options.threads = args.threads;
  options.use_recorded_upstream = args.recorded_upstream;
  options.reconstruct_clock = !args.no_clock;
  options.search_max_cells = args.search_cells;
  return options;
}

// --baseline: calibrate on the baseline, print the calibrated values, diagnose the recordings
// against the calibrated scenario. Every check (baseline against recordings, both against the
// scenario) runs before the calibration, and nothing is written unless both steps succeed.
int run_with_baseline(const scenarios::Scenario& s, const std::vector<Recording>& recordings, const DiagnoseArguments& args) {
  const std::vector<Recording> baseline = read_all_in_mm(args.baseline, args.format);
  check_recorded_upstream(baseline, args);
  if (const auto problems = diagnosis::check_baseline(baseline, recordings); !problems.empty()) {
    throw InputError(problems.front());
  }
  if (const auto problems = diagnosis::check_recordings(s, baseline); !problems.empty()) {
    throw InputError(problems.front() + " (baseline; scenario " + s.name + ")");
  }
  check_diagnosis_cost(s, recordings, baseline, args);
  for (const auto& w : diagnosis::baseline_coverage(baseline, recordings)) std::cerr << "canalsim: warning: " << w << '\n';
  diagnosis::BaselineOptions options;
  options.diagnosis = diagnose_options(args);
  ProgressLine progress("calibrating " + s.name + " on " + std::to_string(baseline.size()) + " baseline recording(s), then diagnosing " +
                        std::to_string(recordings.size()));
  options.progress = progress.callback();
  const diagnosis::BaselineDiagnosis r = diagnosis::diagnose_with_baseline(s, baseline, recordings, options);
  progress.finish();
  if (!r.calibration.ok) {
    std::cerr << "canalsim: error: calibration on the baseline failed: " << r.calibration.message << '\n';
    return 1;
  }
  std::cout << diagnosis::baseline_summary(r);
  return write_outputs(r.diagnosis, args, "canalsim diagnosis: " + s.name + " calibrated on a baseline",
                       diagnosis::baseline_json(r));
}

// A flag of the other mode would be ignored without a word: refuse it.
void check_flags_apply(const DiagnoseArguments& args) {
  const std::vector<std::string> scenario_only = {"--baseline", "--recorded-upstream", "--no-clock", "--allow-long", "--search-cells"};
  const std::vector<std::string> model_only = {"--quantum", "--gate-speed", "--upstream-level"};
  const bool model = !args.model.empty();
  for (const std::string& flag : args.flags_given) {
    const auto& other = model ? scenario_only : model_only;
    if (std::find(other.begin(), other.end(), flag) != other.end()) {
      throw InputError("diagnose " + flag + ": applies to " + (model ? "--scenario" : "--model") + ", not to " +
                       (model ? "--model " + args.model : "--scenario " + args.scenario));
    }
  }
}

int run(const DiagnoseArguments& args) {
  if (args.scenario.empty() == args.model.empty()) {
    throw InputError("diagnose: give exactly one of --scenario S.toml and --model M");
  }
  if (!args.baseline.empty() && !args.model.empty()) {
    throw InputError("diagnose: --baseline calibrates a scenario: use it with --scenario, not --model");
  }
  check_flags_apply(args);
  if (args.recordings.empty()) {
    throw InputError(args.baseline.empty()
                         ? "diagnose: no recordings given (canalsim diagnose --scenario S REC.csv...)"
                         : "diagnose: no recordings to diagnose after the baseline: end the --baseline list with -- "
                           "(canalsim diagnose --scenario S --baseline B1.csv B2.csv -- R1.csv R2.csv) or put --baseline last");
  }
  check_diagnosis_outputs(args);
  if (!args.model.empty()) return run_model(args);
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
  // One line for the first problem (it names the recording); the user reruns to see the next.
  const std::vector<Recording> recordings = read_all_in_mm(args.recordings, args.format);
  check_recorded_upstream(recordings, args);
  if (const auto problems = diagnosis::check_recordings(s, recordings); !problems.empty()) {
    throw InputError(problems.front() + " (scenario " + s.name + ")");
  }

  if (!args.baseline.empty()) return run_with_baseline(s, recordings, args);
  check_diagnosis_cost(s, recordings, {}, args);

  diagnosis::DiagnoseOptions options = diagnose_options(args);
  ProgressLine progress("diagnosing " + std::to_string(recordings.size()) + " recording(s) against " + s.name);
  options.progress = progress.callback();
  const diagnosis::Diagnosis d = diagnosis::diagnose(s, recordings, options);
  progress.finish();
  return write_outputs(d, args, "canalsim diagnosis: " + s.name);
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto args = std::make_shared<DiagnoseArguments>();
  auto* cmd = app.add_subcommand("diagnose", "Locate and explain the mismatch between a scenario and recordings");
  cmd->add_option("--scenario", args->scenario, "Built-in scenario name or TOML file");
  cmd->add_option("--model", args->model,
                  "Diagnose a reduced model instead (liom, sopd, lfom, nliom-f, nlfom-f, nliom-s, nlfom-s, hybrid, id, idz)");
  cmd->add_option("--quantum", args->quantum_mm, "--model: sensor resolution in mm already in the model (Gharab et al. 2019, eq. 17)")
      ->check(number_in(0.0, 100.0, "a resolution in mm"));
  cmd->add_option("--gate-speed", args->gate_speed_mm_s, "--model: gate speed in mm/s already in the model (Gharab et al. 2019, eq. 16)")
      ->check(number_in(0.0, 1e6, "a speed in mm/s"));
  cmd->add_option("--upstream-level", args->upstream_level_mm,
                  "--model: constant upstream level in mm for recordings without y_up_mm")
      ->check(positive_number("a level in mm"));
  cmd->add_option("recordings", args->recordings, "Recording CSV files to diagnose");
  cmd->add_option("--baseline", args->baseline,
                  "--scenario: calibrate the scenario on these clean recordings first, then diagnose the others "
                  "against it; ends at the next option or -- (--baseline B1.csv B2.csv -- R1.csv R2.csv)");
  cmd->add_option("--json", args->json, "Write the diagnosis as JSON");
  args->format.add_options(cmd);
  cmd->add_option("--report", args->report, "Write a self-contained HTML report");
  args->plots.add_option(cmd, "per recording R, R_levels_and_residual.svg, R_residual_autocorrelation.svg and R_step_zoom.svg");
  cmd->add_option("--candidates", args->candidates, "Catalog effects to try, e.g. gate_leakage sensor_offset[y_dwe_mm]; a per-channel effect without [CHANNEL] is tried on every level channel (default: all; docs/diagnosis.md, section 4)")
      ->delimiter(',');
  cmd->add_option("--fit-fraction", args->fit_fraction, "Leading share of each recording used for fitting (default 0.5)")
      ->check(number_in(0.11, 0.89, "a fraction"));
  cmd->add_option("--threads", args->threads, "Recordings simulated in parallel (default 2)")->check(thread_count());
  cmd->add_flag("--recorded-upstream", args->recorded_upstream,
                "Drive the head gate with the recorded y_up_mm instead of the scenario's upstream model");
  cmd->add_flag("--no-clock", args->no_clock,
                "Replay the sampled command as sampled (no reconstruction of a PRBS clock)");
  cmd->add_option("--search-cells", args->search_cells,
                  "--scenario: searches replay on the scenario's grid halved until it has at most this many cells, corrected by "
                  "the nominal model's difference between the grids; judged points replay on the scenario's grid (default 200; "
                  "0 = every replay on the scenario's grid)")
      ->check(integer_in(0, 1000000, "a number of cells"));
  cmd->add_flag("--allow-long", args->allow_long,
                "--scenario: run past the cost ceiling (3e10 cell updates per busy thread over all replays; docs/scenarios.md)");
  cmd->callback([args, cmd] {
    for (const CLI::Option* option : cmd->get_options()) {
      if (option->count() > 0 && !option->get_lnames().empty()) args->flags_given.push_back("--" + option->get_lnames().front());
    }
    const int code = run(*args);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace canalsim::cli
