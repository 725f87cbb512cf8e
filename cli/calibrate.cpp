// `canalsim calibrate --scenario S REC... -o OUT.toml [--params P,...] [--validate REC...]
// [--gate-laws L,...] [--model-forms] [--json F] [--report F.html] [--plots-dir DIR] [--threads N]`: fits scenario parameters to recordings
// (calibration/calibrate.hpp; docs/calibration.md), prints the table and writes the calibrated
// scenario — the input file (or built-in text) with the calibrated keys replaced, each with its
// standard deviation in a comment. Outputs are checked before the work and written atomically
// only when the calibration succeeded.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "calibration/calibrate.hpp"
#include "calibration/report.hpp"
#include "cli/plots_dir.hpp"
#include "calibration/scenario_file.hpp"
#include "cli/checks.hpp"
#include "cli/recording_format.hpp"
#include "cli/commands.hpp"
#include "core/declared_units.hpp"
#include "diagnosis/baseline.hpp"
#include "diagnosis/calibrated_scenario.hpp"
#include "core/files.hpp"
#include "core/format.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/run_cost.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::cli {
namespace {

struct CalibrateArguments {
  std::string scenario;
  std::vector<std::string> recordings, validation, params, channels, gate_laws;
  std::string out, json, report;
  PlotsDirectory plots;
  int threads = 2;
  int starts = 2;
  int grid_refinements = 2;
  bool keep_grid = false;
  bool model_forms = false;
  bool allow_long = false;
  std::string replay = "diagnosis";
  RecordingFormat format;
};

// In millimetres: a command logged in counts (# u_unit, # u_scale_mm_per_unit) is converted here.
std::vector<Recording> read_all(const std::vector<std::string>& files, const RecordingFormat& format) {
  std::vector<Recording> out;
  for (const auto& f : files) out.push_back(in_millimetres(format.read(f)));
  return out;
}

// A calibration replays each recording about 100 times on the scenario's grid (bench/README.md:
// 400–500 simulations for four recordings), and each refinement about half as often again on twice
// the cells, at four times the work a replay (half the cell size, half the time step). Refused
// past one run's ceiling on each thread the replays keep busy (scenarios/run_cost.hpp), before any
// work, unless --allow-long.
void check_calibration_cost(const scenarios::Scenario& s, const std::vector<Recording>& recordings,
                            const std::vector<Recording>& validation, const CalibrateArguments& args) {
  if (args.allow_long) return;
  double grid_factor = 1.0;
  for (int r = 1; r <= args.grid_refinements; ++r) grid_factor += std::pow(4.0, r) / std::pow(2.0, r);
  double updates = 0.0;
  std::size_t samples = 0;
  for (const auto* set : {&recordings, &validation}) {
    for (const Recording& rec : *set) {
      updates += 100.0 * grid_factor * scenarios::estimate_replay_cost(s, rec).cell_updates;
      samples += rec.size();
    }
  }
  const std::size_t parallel = recordings.size() + validation.size();
  if (updates <= scenarios::replays_ceiling(args.threads, parallel)) return;
  throw InputError("calibrate: replaying " + std::to_string(parallel) + " recording(s) of " + std::to_string(samples) +
                   " samples about " + format_g(100.0 * grid_factor, 3) + " times through " + s.name + " is about " +
                   format_g(updates, 3) + " cell updates, expected at most " +
                   scenarios::replays_ceiling_text(args.threads, parallel) +
                   " (shorter recordings, --grid-refinements 0; or pass --allow-long)");
}

int run(const CalibrateArguments& args) {
  std::vector<NamedFile> inputs = named_files("recording", args.recordings);
  for (const NamedFile& v : named_files("--validate recording", args.validation)) inputs.push_back(v);
  inputs.push_back({"--scenario", args.scenario});
  check_outputs({{"-o", args.out}, {"--json", args.json}, {"--report", args.report}}, inputs);
  args.plots.check();
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
  const std::string text = scenarios::scenario_toml_text(args.scenario);
  const std::vector<Recording> recordings = read_all(args.recordings, args.format);
  const std::vector<Recording> validation = read_all(args.validation, args.format);
  if (args.replay == "recorded-upstream") {
    for (const auto* set : {&recordings, &validation}) {
      for (const Recording& r : *set) {
        if (!r.has(columns::upstream_level)) {
          throw InputError(r.source + ": missing column y_up_mm: --replay recorded-upstream drives the head gate with it");
        }
      }
    }
  }
  check_calibration_cost(s, recordings, validation, args);

  calibration::CalibrateOptions options;
  options.parameters = args.params;
  if (args.replay == "diagnosis") {
    // The calibrated scenario is diagnosed next (`diagnose --scenario cal.toml`): calibrate it
    // with the replay the diagnosis uses, or the difference between the two replays shows up as
    // spurious effects (an upstream sensor's offset, absorbed by a discharge coefficient under the
    // recorded-upstream drive, reappears as a sensor offset under the upstream model).
    options.replay = diagnosis::calibration_replay_for_diagnosis();
  }
  if (!args.channels.empty()) options.replay.channels = args.channels;
  options.threads = args.threads;
  options.starts = args.starts;
  options.grid_refinements = args.grid_refinements;
  options.write_grid_converged = !args.keep_grid;
  options.try_model_forms = args.model_forms;
  for (const auto& law : args.gate_laws) {
    options.gate_laws.push_back(law == "swamee" ? scenarios::GateLaw::swamee : scenarios::GateLaw::simple);
  }
  ProgressLine progress("calibrating " + s.name);
  options.progress = progress.callback();
  std::vector<std::string> warnings;
  options.replay.warning = [&warnings](const std::string& w) {
    if (warnings.size() < 3) warnings.push_back(w);
  };
  const calibration::Calibration c = calibration::calibrate(s, recordings, validation, options);
  progress.finish();
  for (const auto& w : warnings) std::cerr << "canalsim: warning: " << w << '\n';
  std::cout << calibration::text_summary(c);
  if (!c.ok) {
    std::cerr << "canalsim: error: calibration failed: " << c.message << '\n';
    return 1;
  }
  // The scenario, the JSON, the report and the plots are one set, written all or nothing.
  std::vector<std::string> recording_names;
  for (const auto& r : args.recordings) recording_names.push_back(std::filesystem::path(r).filename().string());
  std::vector<FileContents> outputs{
      {args.out, diagnosis::calibrated_scenario_toml(text, c, {args.scenario, recording_names, args.out})}};
  if (!args.json.empty()) outputs.emplace_back(args.json, calibration::to_json(c).dump(2) + "\n");
  if (!args.report.empty()) {
    outputs.emplace_back(args.report, calibration::html_report(c, "canalsim calibration: " + s.name));
  }
  outputs = args.plots.write(std::move(outputs), args.plots.dir.empty() ? std::vector<plot::Figure>{} : calibration::report_figures(c));
  for (const auto& [file, contents] : outputs) std::cout << "wrote " << file.string() << '\n';
  return 0;
}

}  // namespace

void add_calibrate_command(CLI::App& app) {
  auto args = std::make_shared<CalibrateArguments>();
  auto* cmd = app.add_subcommand("calibrate", "Fit a scenario's uncertain parameters to recordings");
  cmd->add_option("--scenario", args->scenario, "Built-in scenario name or TOML file")->required();
  cmd->add_option("recordings", args->recordings, "Recording CSV files to fit")->required();
  cmd->add_option("-o,--out", args->out, "Write the calibrated scenario (TOML)")->required();
  cmd->add_option("--params", args->params,
                  "Parameters to fit, NAME or NAME:LOW:HIGH, comma-separated (default: the scenario's unknowns; "
                  "+NAME adds one to them; docs/calibration.md)")
      ->delimiter(',');
  cmd->add_option("--channels", args->channels,
                  "Channels compared, comma-separated (default y_dwe_mm,y_dw_mm,y_up_mm,q_lps; those a recording "
                  "lacks are skipped)")
      ->delimiter(',')
      ->check(CLI::IsMember({"y_dwe_mm", "y_dw_mm", "y_up_mm", "x_up_mm", "q_lps"}));
  cmd->add_option("--gate-laws", args->gate_laws,
                  "Gate laws to compare, comma-separated: each is put at every sluice gate and calibrated, the best "
                  "kept (swamee: Swamee 1992; simple: the paper's eqs. 9/11; default: the scenario's own)")
      ->delimiter(',')
      ->check(CLI::IsMember({"swamee", "simple"}));
  cmd->add_option("--validate", args->validation, "Recordings to check the calibration on, not fitted");
  cmd->add_option("--json", args->json, "Write the calibration as JSON");
  args->format.add_options(cmd);
  cmd->add_option("--report", args->report, "Write a self-contained HTML report");
  args->plots.add_option(cmd, "per recording R and level channel C, R_C_levels_and_residual.svg, R_C_residual_autocorrelation.svg, "
                              "R_C_step_zoom.svg and R_C_residual_spectrum.svg (R_validation_C_… for --validate recordings)");
  cmd->add_option("--threads", args->threads, "Simulations in parallel (default 2)")->check(thread_count());
  cmd->add_option("--starts", args->starts, "Levenberg-Marquardt starts (default 2)")->check(integer_in(1, 10, "a number of starts"));
  cmd->add_option("--grid-refinements", args->grid_refinements,
                  "Calibrate again on twice the cells while that lowers the cost by more than a third, at most N times "
                  "(default 2; 0: the scenario's grid; docs/calibration.md)")
      ->check(integer_in(0, 3, "a number of refinements"));
  cmd->add_flag("--allow-long", args->allow_long,
                "Run past the cost ceiling (3e10 cell updates per busy thread over all replays; docs/scenarios.md)");
  cmd->add_flag("--keep-grid", args->keep_grid,
                "Write the estimates on the last grid calibrated on, even when the grid-converged estimates on twice "
                "or four times its cells fit the recordings better (by default those are written when they lower the cost by a "
                "tenth; docs/calibration.md)");
  cmd->add_flag("--model-forms", args->model_forms,
                "Then add each model-form choice left open (the head gate's rating, zero-head regularisation and "
                "regime border's floor, a time offset between command and levels, a weir, the tail level, the pump) "
                "and refit from the estimates, on the scenario's grid and on twice its cells: the cost each removes "
                "and its information criterion (docs/calibration.md)");
  cmd->add_option("--replay", args->replay,
                  "diagnosis: replay the recordings as `diagnose` does (the upstream model drives the head gate; "
                  "for a scenario diagnosed next); recorded-upstream: drive the head gate with the recorded y_up_mm "
                  "and start at each recording's own levels (docs/calibration.md)")
      ->capture_default_str()
      ->check(CLI::IsMember({"diagnosis", "recorded-upstream"}));
  cmd->callback([args] {
    const int code = run(*args);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace canalsim::cli
