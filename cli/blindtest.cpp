// `canalsim blindtest --trials N --seed S [--json F]`: conceals one catalog effect (or none) per
// trial in the laboratory canal, simulates op1–op4 with it, diagnoses blind and prints the
// confusion matrix, top-1 accuracy, false alarms, parameter error and held-out fit gain.
#include <cmath>
#include <limits>
#include <iostream>
#include <memory>

#include "cli/checks.hpp"
#include "cli/commands.hpp"
#include "cluster/distribute.hpp"
#include "diagnosis/blindtest.hpp"
#include "reduced_models/models.hpp"
#include "scenarios/builtin.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"

namespace canalsim::cli {
namespace {

struct BlindtestArguments {
  int trials = 40;
  std::uint64_t seed = 1;
  std::string json;
  std::string scenario = "lab";
  int threads = 2;
  double duration = 0.0;
  std::vector<std::string> experiments = {"op1", "op2", "op3", "op4"};
  std::vector<std::string> effects;
  std::vector<int> only;
  bool verbose = false;
  bool realistic = false;
  int two_effect_trials = 10;
  std::string truth_scheme = "finite-volume";
  std::string model;
  double quantum_mm = 0.05;
};

void run(const BlindtestArguments& args) {
  check_outputs({{"--json", args.json}}, {{"--scenario", args.scenario}});  // written after every trial has run
  const scenarios::Scenario s = scenarios::load_scenario_or_builtin(args.scenario);
  // --duration shortens the experiments; longer than one of them it would ask for a run the
  // experiment does not have.
  for (const auto& name : args.experiments) {
    const auto* e = s.find_experiment(name);
    if (e && args.duration > e->duration_s) {
      throw InputError("--duration " + format_g(args.duration) + ": longer than experiment " + name + " of " + s.name + " (" +
                       format_g(e->duration_s) + " s): expected at most " + format_g(e->duration_s) +
                       " s (it shortens the experiments; 0 for their full length)");
    }
  }
  diagnosis::BlindtestOptions options;
  options.trials = args.trials;
  options.seed = args.seed;
  options.threads = args.threads;
  options.duration_s = args.duration;
  options.experiments = args.experiments;
  options.effects = args.effects;
  options.only = args.only;
  if (!args.model.empty()) {
    diagnosis::ModelDiagnoseOptions m;
    m.kind = reduced::require_model_kind(args.model);
    m.quantum_mm = args.quantum_mm;
    options.model = m;
    if (options.effects.empty()) options.effects = {"gate_rate_limit", "sensor_quantization"};
  }
  if (args.realistic) {
    diagnosis::RealisticTruth realistic;
    realistic.two_effect_trials = args.two_effect_trials;
    if (args.truth_scheme == "staggered") realistic.scheme = diagnosis::TruthScheme::staggered;
    options.realistic = realistic;
  }
  if (const Status status = options.validate(); !status) throw InputError("blindtest: " + status.message());
  const int total = args.only.empty() ? args.trials + (args.realistic ? args.two_effect_trials : 0)
                                      : static_cast<int>(args.only.size());
  // Under mpirun every process runs trials; rank 0 alone reports them (cluster/distribute.hpp).
  if (!cluster::is_root()) {
    diagnosis::run_blindtest(s, options);
    return;
  }
  const std::string threads = std::to_string(args.threads) + (args.threads == 1 ? " thread" : " threads");
  const std::string where =
      cluster::processes() > 1 ? std::to_string(cluster::processes()) + " processes of " + threads : threads;
  ProgressLine progress(std::string(args.realistic ? "realistic " : "") + "blind test, " + std::to_string(total) +
                        " trials on " + where);
  options.progress = progress.callback();
  const diagnosis::BlindtestResult result = diagnosis::run_blindtest(s, options);
  progress.finish();
  std::cout << diagnosis::format_blindtest(result, options);
  if (args.verbose) {
    std::cout << "\ntrial  concealed              value  verdict                estimate   error   gain\n";
    for (const auto& t : result.trials) {
      // No estimate to compare where the verdict is another effect or the effect has no row.
      const bool estimated = std::isfinite(t.parameter_error);
      const double none = std::numeric_limits<double>::quiet_NaN();
      const std::string estimate = format_figure(estimated ? t.estimate : none, 3);
      const std::string error = format_figure(100.0 * t.parameter_error, 1, "%");
      const std::string gain = (t.heldout_gain > 0.0 ? "+" : "") + format_figure(t.heldout_gain, 2);
      std::printf("%5d  %-21s %6.3f  %-21s %9s %7s %7s %s\n", t.index, t.truth.effect.c_str(), t.truth.value,
                  t.verdict.c_str(), estimate.c_str(), error.c_str(), gain.c_str(), t.message.c_str());
      if (t.second) {
        std::string named;
        for (const auto& n : t.named) named += (named.empty() ? "" : ", ") + n.effect;
        std::printf("       + %-19s %6.3f  named: %s (%s)\n", t.second->effect.c_str(), t.second->value,
                    named.empty() ? "nothing" : named.c_str(), t.both_named ? "both" : "not both");
      }
      if (!t.truth_drawn.empty()) {
        std::printf("       truth: %s\n       %.1f s: recordings %.1f s, calibration %.1f s, diagnosis %.1f s\n",
                    t.truth_drawn.c_str(), t.seconds, t.simulation_seconds, t.calibration_seconds,
                    t.seconds - t.simulation_seconds - t.calibration_seconds);
      }
    }
  }
  if (!args.json.empty()) {
    write_file_atomically(args.json, diagnosis::to_json(result).dump(2) + "\n");
    std::cout << "wrote " << args.json << '\n';
  }
}

// 0 means the full experiment; shorter than 20 s leaves too few PRBS periods to diagnose
// (BlindtestOptions::validate).
CLI::Validator duration_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = -1.0;
        if (detail::parse_number(text, v) && (v == 0.0 || v >= 20.0)) return "";
        return "expected a number of seconds >= 20 (or 0 for the full experiments), got " + text;
      },
      "0 or >= 20");
}

}  // namespace

void add_blindtest_command(CLI::App& app) {
  auto args = std::make_shared<BlindtestArguments>();
  auto* cmd = app.add_subcommand("blindtest", "Conceal effects in simulated experiments and score the diagnosis");
  cmd->add_option("--trials", args->trials, "Number of trials (default 40)")->check(integer_in(1, 100000, "a number of trials"));
  cmd->add_option("--seed", args->seed, "Random seed (default 1)")->check(seed_value());
  cmd->add_option("--json", args->json, "Write per-trial results and the summary as JSON");
  cmd->add_option("--scenario", args->scenario, "Scenario (default: the built-in lab canal)");
  cmd->add_option("--threads", args->threads, "Trials in parallel (default 2)")->check(thread_count());
  cmd->add_option("--duration", args->duration, "Shorten every experiment to this many seconds, >= 20 (default: full)")
      ->check(duration_check());
  cmd->add_option("--experiments", args->experiments, "Experiments simulated per trial, by spaces or commas (default op1 op2 op3 op4)")
      ->delimiter(',');
  cmd->add_option("--effects", args->effects, "Draw only these effects (and none), by spaces or commas: catalog rows (a per-channel row goes on a drawn level channel), sensor_offset[y_dwe_mm], or with --realistic gate_backlash and depth_seepage; default the whole catalog, and with --realistic those two")
      ->delimiter(',');
  cmd->add_option("--only", args->only,
                  "Run only these trials of the drawn set, by index (spaces or commas): each is the trial of the full "
                  "test, e.g. a miss re-run with -v")
      ->delimiter(',');
  cmd->add_flag("--verbose,-v", args->verbose, "Print every trial");
  cmd->add_flag("--realistic", args->realistic,
                "Truth simulated differently (4x cells, other limiter and Courant number) with perturbed "
                "physics; calibrate on a clean baseline of it, then diagnose (docs/diagnosis.md)");
  cmd->add_option("--two-effect-trials", args->two_effect_trials,
                  "--realistic: trials with two concealed effects added to --trials (default 10)")
      ->check(integer_in(0, 100000, "a number of trials"));
  cmd->add_option("--truth-scheme", args->truth_scheme,
                  "--realistic: finite-volume (canalsim's scheme, 4x the cells, the other limiter) or staggered (the "
                  "second simulator: another scheme and gate-law regularisation, one-pool canals; docs/numerics.md)")
      ->check(CLI::IsMember({"finite-volume", "staggered"}))
      ->capture_default_str();
  cmd->add_option("--model", args->model,
                  "Diagnose against this reduced model instead of the scenario (draws gate_rate_limit and "
                  "sensor_quantization unless --effects says otherwise)");
  cmd->add_option("--quantum", args->quantum_mm, "--model: sensor resolution in mm in the model (default 0.05)")
      ->check(number_in(0.0, 100.0, "a resolution in mm"));
  cmd->callback([args, cmd] {
    // A flag of a mode not chosen would be ignored without a word.
    if (cmd->count("--two-effect-trials") > 0 && !args->realistic) {
      throw InputError("blindtest --two-effect-trials: applies to --realistic");
    }
    if (cmd->count("--truth-scheme") > 0 && !args->realistic) throw InputError("blindtest --truth-scheme: applies to --realistic");
    if (cmd->count("--quantum") > 0 && args->model.empty()) throw InputError("blindtest --quantum: applies to --model");
    run(*args);
  });
}

}  // namespace canalsim::cli
