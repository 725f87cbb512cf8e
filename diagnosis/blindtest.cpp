#include "diagnosis/blindtest.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <numeric>
#include <sstream>

#include "cluster/archive.hpp"
#include "cluster/distribute.hpp"
#include "core/json.hpp"
#include "core/format.hpp"
#include "diagnosis/blindtest_trial.hpp"
#include "scenarios/outside_catalog.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::diagnosis {
namespace {

double uniform(std::mt19937_64& rng, double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
bool coin(std::mt19937_64& rng) { return std::bernoulli_distribution(0.5)(rng); }

// A class of the confusion matrix: a catalog row (an effect without its channel), none,
// unexplained or failed.
std::string class_of(const std::string& name) { return name.substr(0, name.find('[')); }

std::string short_name(const std::string& name) {
  if (name == "unexplained") return "unexpl";
  if (name == "gate_backlash") return "backlash";
  if (name == "depth_seepage") return "seepage";
  if (const EffectKind* k = kind_named(class_of(name))) return k->label;
  return name.substr(0, 7);
}

std::vector<std::string> effect_names(const BlindtestOptions& o) {
  if (!o.effects.empty()) return o.effects;
  std::vector<std::string> out;
  for (const auto& e : catalog()) out.push_back(e.name);
  if (o.realistic && o.realistic->outside_catalog) {
    for (const auto& e : outside_catalog_effects()) out.push_back(e);
  }
  return out;
}

}  // namespace

Status BlindtestOptions::validate() const {
  Validator check;
  check.require(trials >= 1, "trials", trials, ">= 1");
  check.require(threads >= 1, "threads", threads, ">= 1");
  check.require(!experiments.empty(), "experiments", "expected at least one");
  check.require(duration_s == 0.0 || duration_s >= 20.0, "duration_s", duration_s, "0 or >= 20");
  check.require(noise_std_mm >= 0.0, "noise_std_mm", noise_std_mm, ">= 0");
  for (const auto& e : effects) {
    const bool outside = std::find(outside_catalog_effects().begin(), outside_catalog_effects().end(), e) !=
                         outside_catalog_effects().end();
    check.require(effect_from_name(e).has_value() || kind_named(e) != nullptr || outside, "effects",
                  "unknown effect '" + e + "' (expected one of " + catalog_names() + ")");
  }
  const int drawn = trials + (realistic ? realistic->two_effect_trials : 0);
  for (int index : only) {
    check.require(index >= 0 && index < drawn, "only", index, "a trial index in 0.." + std::to_string(drawn - 1));
  }
  check.nested("diagnose", diagnose.validate());
  check.require(!(model && realistic), "realistic", "not with a reduced model (the realistic test calibrates a scenario)");
  if (realistic) check.nested("realistic", realistic->validate());
  return check.status();
}

Status RealisticTruth::validate() const {
  Validator check;
  check.require(numerics.cells_factor >= 1 && numerics.cells_factor <= 16, "numerics.cells_factor",
                numerics.cells_factor, "1..16");
  check.require(numerics.cfl > 0.0 && numerics.cfl <= 1.0, "numerics.cfl", numerics.cfl, "(0, 1]");
  check.require(staggered.cells >= 3 && staggered.cells <= 100000, "staggered.cells", staggered.cells, "3..100000");
  check.require(noise_low_mm >= 0.0 && noise_low_mm <= noise_high_mm, "noise_low_mm", noise_low_mm,
                "[0, noise_high_mm]");
  check.require(two_effect_trials >= 0, "two_effect_trials", two_effect_trials, ">= 0");
  for (const auto& [key, value] : {std::pair{"discharge_coefficient", tolerances.discharge_coefficient},
                                   std::pair{"manning_n", tolerances.manning_n}}) {
    check.require(value >= 0.0 && value < 0.9, std::string("tolerances.") + key, value, "[0, 0.9)");
  }
  for (const auto& [key, value] : {std::pair{"downstream_opening_mm", tolerances.downstream_opening_mm},
                                   std::pair{"tail_level_mm", tolerances.tail_level_mm},
                                   std::pair{"level_offset_mm", tolerances.level_offset_mm}}) {
    check.require(value >= 0.0 && value <= 10.0, std::string("tolerances.") + key, value, "[0, 10]");
  }
  check.nested("baseline", baseline.validate());
  return check.status();
}

const std::vector<std::string>& outside_catalog_effects() {
  static const std::vector<std::string> names = {"gate_backlash", "depth_seepage"};
  return names;
}

ConcealedEffect draw_effect(const std::string& name, std::mt19937_64& rng, const std::vector<std::string>& level_channels) {
  if (name == "none") return {"none", 0.0};
  if (name == "gate_backlash") return {name, uniform(rng, 1.5, 4.0)};
  if (name == "depth_seepage") return {name, uniform(rng, 0.06, 0.15)};
  Effect effect;
  if (const auto concrete = effect_from_name(name)) {
    effect = *concrete;
  } else {
    effect.kind = kind_named(name);
    if (!effect.kind) throw std::invalid_argument("blindtest: unknown effect '" + name + "'");
    if (effect.kind->scope == Scope::each_level_channel) {
      if (level_channels.empty()) throw std::invalid_argument("blindtest: " + name + " needs a level channel");
      effect.channel = level_channels[std::uniform_int_distribution<std::size_t>(0, level_channels.size() - 1)(rng)];
    }
  }
  const BlindDraw& d = effect.kind->draw;
  const double magnitude = uniform(rng, d.low, d.high);
  const double sign = d.either_sign && coin(rng) ? -1.0 : 1.0;
  return {effect.name(), to_parameter(effect, effect.kind->theta_none + sign * magnitude)};
}

void conceal(const ConcealedEffect& truth, scenarios::Scenario& s, double inflow_m3s) {
  if (truth.effect == "depth_seepage") scenarios::add_depth_seepage(s, truth.value);
  const auto effect = effect_from_name(truth.effect);
  if (effect && effect->kind->acts == Acts::hydraulics) apply_effect(*effect, truth.value, s, inflow_m3s);
}

double parameter_error(const ConcealedEffect& truth, double estimate) {
  if (truth.effect == "none") return std::numeric_limits<double>::quiet_NaN();
  const auto effect = effect_from_name(truth.effect);
  const double none = effect ? no_effect_parameter(*effect) : 0.0;
  const double reference = std::isfinite(none) ? truth.value - none : truth.value;
  return std::abs(estimate - truth.value) / std::max(std::abs(reference), 1e-12);
}

bool names_effect(const std::string& verdict, const std::string& concealed, bool gate_position_recorded) {
  if (verdict == concealed) return true;
  const auto effect = effect_from_name(concealed);
  const char* twin = effect ? effect->kind->twin_without_gate_position : nullptr;
  return !gate_position_recorded && twin && verdict == twin;
}

// A trial's fields as they travel from the process that ran it to rank 0 (cluster/archive.hpp).
template <class Archive>
void fields(Archive& a, EffectValue& e) {
  a(e.effect, e.value);
}
template <class Archive>
void fields(Archive& a, Trial& t) {
  a(t.index, t.truth, t.second, t.verdict, t.reason, t.form, t.named, t.both_named, t.truth_drawn, t.estimate,
    t.channel_right, t.below_threshold, t.truth_location, t.located, t.signature_rms_mm, t.model_error_mm,
    t.below_model_error, t.parameter_error, t.heldout_gain, t.correct, t.seconds, t.simulation_seconds,
    t.calibration_seconds, t.message);
}

namespace {

// The experiments every trial records, shortened to the test's duration.
std::vector<scenarios::ExperimentSpec> trial_experiments(const scenarios::Scenario& base, const BlindtestOptions& o) {
  std::vector<scenarios::ExperimentSpec> experiments;
  for (const auto& name : o.experiments) {
    const auto* e = base.find_experiment(name);
    if (!e) throw InputError(base.source + ": no experiment '" + name + "' for the blind test");
    scenarios::ExperimentSpec copy = *e;
    if (o.duration_s > 0.0) copy.duration_s = o.duration_s;
    experiments.push_back(copy);
  }
  return experiments;
}

// Inflow at each operating point (the reference of lateral_outflow): from the nominal steady state.
std::vector<double> operating_inflows(const scenarios::Scenario& base, const std::vector<scenarios::ExperimentSpec>& experiments) {
  std::vector<double> inflow(experiments.size(), 0.0);
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    scenarios::ExperimentSpec steady = experiments[i];
    steady.input.kind = scenarios::InputKind::constant;
    steady.duration_s = 2.0;
    const Recording r = scenarios::simulate(base, steady);
    inflow[i] = r.column(columns::discharge).front() * 1e-3;
  }
  return inflow;
}

// The trials' concealed effects: balanced classes, shuffled blocks of every class; then, for the
// realistic test, two different effects of the catalog at once, drawn after the single ones so
// that those stay the same whatever their number.
std::vector<Trial> draw_trials(const BlindtestOptions& o, const std::vector<std::string>& classes) {
  std::mt19937_64 rng(o.seed);
  // Instrument faults go on one level channel of those the trial's recordings carry (a reduced
  // model reads y_dwe_mm alone).
  const std::vector<std::string> levels =
      o.model ? std::vector<std::string>{columns::level_downstream_end}
              : std::vector<std::string>{columns::upstream_level, columns::level_below_gate, columns::level_downstream_end};
  std::vector<Trial> trials;
  while (trials.size() < static_cast<std::size_t>(o.trials)) {
    std::vector<std::string> block = classes;
    std::shuffle(block.begin(), block.end(), rng);
    for (const auto& c : block) {
      if (trials.size() < static_cast<std::size_t>(o.trials)) {
        Trial t;
        t.truth = draw_effect(c, rng, levels);
        trials.push_back(std::move(t));
      }
    }
  }
  const std::vector<std::string> effects = effect_names(o);
  for (int k = 0; o.realistic && k < o.realistic->two_effect_trials && effects.size() >= 2; ++k) {
    const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
    const std::size_t a = pick(effects.size());
    std::size_t b = pick(effects.size() - 1);
    if (b >= a) ++b;
    Trial t;
    t.truth = draw_effect(effects[a], rng, levels);
    t.second = draw_effect(effects[b], rng, levels);
    trials.push_back(std::move(t));
  }
  for (std::size_t i = 0; i < trials.size(); ++i) trials[i].index = static_cast<int>(i);
  return trials;
}

// Runs every trial over the processes of the job (cluster/distribute.hpp), o.threads at a time in
// each; rank 0 receives them all. Each trial catches its own failure (verdict "failed"), so one
// bad trial does not end the test. A trial's outcome depends on its index only, not on the
// process or thread that ran it.
void run_trials(const blind::TrialContext& context, std::vector<Trial>& trials, const BlindtestOptions& o) {
  const auto run_one = [&](std::size_t i) {
    Trial trial = trials[i];
    const auto t0 = std::chrono::steady_clock::now();
    try {
      blind::run_trial(context, trial);
    } catch (const std::exception& ex) {
      trial.verdict = "failed";
      trial.message = ex.what();
    }
    trial.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return cluster::archive(trial);
  };
  ProgressCounter progress(o.progress, trials.size());
  cluster::DistributeOptions distribution;
  distribution.threads = o.threads;
  distribution.on_result = [&](std::size_t, const std::string&) { progress.finished("trials"); };
  const std::vector<std::string> outcomes = cluster::distribute(trials.size(), run_one, distribution);
  if (!cluster::is_root()) return;
  for (std::size_t i = 0; i < trials.size(); ++i) cluster::unarchive(outcomes[i], trials[i]);
}

// The confusion matrix (rows: the drawn classes; columns: those and `unexplained`) and the
// scores of the result's trials.
void tally(const std::vector<std::string>& classes, BlindtestResult& result) {
  for (const auto& c : classes) {
    if (std::find(result.classes.begin(), result.classes.end(), class_of(c)) == result.classes.end()) {
      result.classes.push_back(class_of(c));
    }
  }
  const std::size_t rows = result.classes.size();
  result.classes.push_back("unexplained");
  const auto index_of = [&](const std::string& name) {
    const auto it = std::find(result.classes.begin(), result.classes.end(), name);
    return it == result.classes.end() ? result.classes.size() - 1 : static_cast<std::size_t>(it - result.classes.begin());
  };
  result.confusion.assign(rows, std::vector<int>(result.classes.size(), 0));
  std::vector<double> errors, gains;
  double total_seconds = 0.0;
  for (const auto& t : result.trials) {
    total_seconds += t.seconds;
    if (t.second) {
      ++result.two_effect_trials;
      result.two_effect_both += t.both_named;
      continue;
    }
    result.confusion[index_of(class_of(t.truth.effect))][index_of(class_of(t.verdict))]++;
    result.correct += t.correct;
    result.below_threshold += t.below_threshold;
    if (!t.truth_location.empty()) {
      ++result.outside_trials;
      result.outside_located += t.correct;
      result.outside_below_model_error += t.below_model_error;
    }
    if (t.truth.effect.find('[') != std::string::npos) {
      ++result.channel_trials;
      result.channel_right += t.channel_right;
    }
    if (t.truth.effect == "none") {
      ++result.clean_trials;
      result.false_alarms += t.verdict != "none";
      continue;
    }
    ++result.effect_trials;
    if (!t.correct) continue;
    ++result.effect_correct;
    // A correct `none` (below threshold) or an unexplained residual located right names no
    // parameter to compare.
    if (!std::isfinite(t.parameter_error)) continue;
    ++result.estimated;
    errors.push_back(t.parameter_error);
    gains.push_back(t.heldout_gain);
    result.within_25 += t.parameter_error <= 0.25;
    result.gain_positive += t.heldout_gain > 0.0;
  }
  const std::size_t single = result.trials.size() - static_cast<std::size_t>(result.two_effect_trials);
  result.accuracy = static_cast<double>(result.correct) / static_cast<double>(std::max<std::size_t>(single, 1));
  result.false_alarm_rate = result.clean_trials ? static_cast<double>(result.false_alarms) / result.clean_trials : 0.0;
  if (!errors.empty()) {
    std::sort(errors.begin(), errors.end());
    result.median_parameter_error = errors[errors.size() / 2];
    result.max_parameter_error = errors.back();
    result.mean_heldout_gain = std::accumulate(gains.begin(), gains.end(), 0.0) / static_cast<double>(gains.size());
    std::vector<double> sorted = gains;
    std::sort(sorted.begin(), sorted.end());
    result.median_heldout_gain = sorted[sorted.size() / 2];
    result.min_heldout_gain = *std::min_element(gains.begin(), gains.end());
  }
  result.mean_trial_seconds = total_seconds / static_cast<double>(std::max<std::size_t>(result.trials.size(), 1));
}

}  // namespace

BlindtestResult run_blindtest(const scenarios::Scenario& base, const BlindtestOptions& o) {
  if (const Status status = o.validate(); !status) throw InputError("blindtest options: " + status.message());
  const auto started = std::chrono::steady_clock::now();
  const std::vector<scenarios::ExperimentSpec> experiments = trial_experiments(base, o);
  const std::vector<double> inflow = operating_inflows(base, experiments);
  std::vector<std::string> classes;
  if (o.include_none) classes.push_back("none");
  for (const auto& e : effect_names(o)) classes.push_back(e);

  BlindtestResult result;
  result.trials = draw_trials(o, classes);
  if (!o.only.empty()) {
    std::erase_if(result.trials, [&](const Trial& t) { return std::find(o.only.begin(), o.only.end(), t.index) == o.only.end(); });
  }
  blind::TrialContext context{base, experiments, inflow, o, o.diagnose};
  context.diagnose.threads = 1;
  context.diagnose.progress = nullptr;
  run_trials(context, result.trials, o);
  if (!cluster::is_root()) return {};  // rank 0 holds the trials and reports them
  tally(classes, result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

std::string format_blindtest(const BlindtestResult& r, const BlindtestOptions& o) {
  std::ostringstream s;
  char buf[512];
  s << (o.realistic ? "Realistic diagnosis blind test: " : "Diagnosis blind test: ") << r.trials.size()
    << " trials, seed " << o.seed << ", experiments";
  for (const auto& e : o.experiments) s << ' ' << e;
  s << (o.duration_s > 0.0 ? " (" + format_g(o.duration_s) + " s)" : "")
    << (o.realistic ? "" : ", level noise " + format_g(o.noise_std_mm) + " mm") << '\n';
  if (o.realistic) {
    const RealisticTruth& t = *o.realistic;
    s << "truth: "
      << (t.scheme == TruthScheme::staggered
              ? "the second simulator (staggered scheme, " + std::to_string(t.staggered.cells) + " cells, its own gate-law regularisation)"
              : std::to_string(t.numerics.cells_factor) + "x the cells, the other limiter, Courant " + format_g(t.numerics.cfl))
      << "; Cd ±" << format_g(100 * t.tolerances.discharge_coefficient) << " %, Manning n ±"
      << format_g(100 * t.tolerances.manning_n) << " %, downstream opening ±" << format_g(t.tolerances.downstream_opening_mm)
      << " mm, tail level ±" << format_g(t.tolerances.tail_level_mm) << " mm, level offsets ±"
      << format_g(t.tolerances.level_offset_mm) << " mm, noise " << format_g(t.noise_low_mm) << "–"
      << format_g(t.noise_high_mm) << " mm; levels and command only;\n"
      << "diagnosed against the scenario calibrated on a clean baseline of the same truth (other PRBS)\n";
  }
  s << "\nconfusion matrix (rows: concealed effect, columns: verdict; one-effect and clean trials)\n";
  std::snprintf(buf, sizeof buf, "%-8s", "");
  s << buf;
  for (const auto& c : r.classes) {
    std::snprintf(buf, sizeof buf, "%8s", short_name(c).c_str());
    s << buf;
  }
  s << '\n';
  for (std::size_t i = 0; i < r.confusion.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%-8s", short_name(r.classes[i]).c_str());
    s << buf;
    for (int v : r.confusion[i]) {
      std::snprintf(buf, sizeof buf, "%8s", v ? std::to_string(v).c_str() : ".");
      s << buf;
    }
    s << '\n';
  }
  std::string legend;
  for (const auto& c : r.classes) {
    if (const EffectKind* k = kind_named(c)) legend += (legend.empty() ? "" : ", ") + std::string(k->label) + " = " + k->name;
  }
  s << "\n(" << legend << (legend.empty() ? "" : ", ") << "unexpl = unexplained)\n\n";
  // No estimate at all: its median and maximum are not defined, not 0%.
  const auto percent = [&](double v) {
    return format_figure(r.estimated > 0 ? 100.0 * v : std::numeric_limits<double>::quiet_NaN(), 1, "%");
  };
  // A rate over no clean trials is undefined, not 0%.
  char rate[64];
  std::snprintf(rate, sizeof rate, "%d/%d = %.1f%%", r.false_alarms, r.clean_trials, 100.0 * r.false_alarm_rate);
  const std::string false_alarms = r.clean_trials > 0 ? rate : "n/a (no clean trials)";
  std::snprintf(buf, sizeof buf,
                "top-1 accuracy          %d/%zu = %.1f%% (effect trials %d/%d)\n"
                "false alarms (clean)    %s\n"
                "parameter error         median %s, max %s, within 25%%: %d/%d correct attributions with an estimate\n"
                "held-out Nrmse gain     median %+.2f points, min %+.2f, improved in %d/%d of them\n"
                "time                    %.1f s total, %.1f s per trial (one diagnosis of %zu recordings + their simulation)\n",
                r.correct, r.trials.size() - static_cast<std::size_t>(r.two_effect_trials), 100.0 * r.accuracy, r.effect_correct, r.effect_trials,
                false_alarms.c_str(), percent(r.median_parameter_error).c_str(), percent(r.max_parameter_error).c_str(),
                r.within_25, r.estimated, r.median_heldout_gain, r.min_heldout_gain, r.gain_positive, r.estimated,
                r.seconds, r.mean_trial_seconds, o.experiments.size());
  s << buf;
  if (r.below_threshold > 0) {
    std::snprintf(buf, sizeof buf, "none below threshold    %d of the correct verdicts are `none` on an effect below its reported threshold\n",
                  r.below_threshold);
    s << buf;
  }
  if (r.outside_trials > 0) {
    std::snprintf(buf, sizeof buf, "outside the catalog     %d/%d = %.1f%% right: %d located (unexplained residual on the right channel and regime), "
                  "%d `none` on an effect below the calibrated model's own error\n",
                  r.outside_located, r.outside_trials, 100.0 * r.outside_located / r.outside_trials,
                  r.outside_located - r.outside_below_model_error, r.outside_below_model_error);
    s << buf;
  }
  if (r.channel_trials > 0) {
    std::snprintf(buf, sizeof buf, "faulty channel named    %d/%d = %.1f%% of the one-channel instrument faults\n",
                  r.channel_right, r.channel_trials, 100.0 * r.channel_right / r.channel_trials);
    s << buf;
  }
  if (r.two_effect_trials > 0) {
    std::snprintf(buf, sizeof buf, "two effects at once     both named in %d/%d = %.1f%%\n", r.two_effect_both,
                  r.two_effect_trials, 100.0 * r.two_effect_both / r.two_effect_trials);
    s << buf;
  }
  return s.str();
}


nlohmann::json to_json(const BlindtestResult& r) {
  using nlohmann::json;
  json trials = json::array();
  for (const auto& t : r.trials) {
    json named = json::array(), named_values = json::array();
    for (const auto& n : t.named) {
      named.push_back(n.effect);
      named_values.push_back(n.value);
    }
    trials.push_back({{"trial", t.index}, {"concealed", t.truth.effect}, {"value", t.truth.value},
                      {"verdict", t.verdict}, {"reason", t.reason}, {"form", t.form}, {"correct", t.correct}, {"channel_right", t.channel_right}, {"estimate", json_number(t.estimate)},
                      {"parameter_error", json_number(t.parameter_error)}, {"heldout_gain", json_number(t.heldout_gain)},
                      {"seconds", t.seconds}, {"message", t.message}, {"named", named}, {"named_values", named_values}});
    if (t.second) {
      trials.back()["second"] = {{"concealed", t.second->effect}, {"value", t.second->value}};
      trials.back()["both_named"] = t.both_named;
    }
    if (!t.truth_drawn.empty()) trials.back()["truth"] = t.truth_drawn;
    if (!t.truth_location.empty()) {
      trials.back()["truth_location"] = t.truth_location;
      trials.back()["located"] = t.located;
      trials.back()["signature_rms_mm"] = json_number(t.signature_rms_mm);
      trials.back()["model_error_mm"] = json_number(t.model_error_mm);
      trials.back()["below_model_error"] = t.below_model_error;
    }
    trials.back()["below_threshold"] = t.below_threshold;
  }
  return json{{"classes", r.classes}, {"confusion", r.confusion}, {"accuracy", r.accuracy},
              {"effect_trials", r.effect_trials}, {"effect_correct", r.effect_correct},
              {"clean_trials", r.clean_trials}, {"false_alarms", r.false_alarms},
              {"false_alarm_rate", r.false_alarm_rate}, {"estimated", r.estimated}, {"within_25", r.within_25},
              {"median_parameter_error", r.median_parameter_error}, {"max_parameter_error", r.max_parameter_error},
              {"gain_positive", r.gain_positive}, {"mean_heldout_gain", r.mean_heldout_gain}, {"median_heldout_gain", r.median_heldout_gain},
              {"min_heldout_gain", r.min_heldout_gain}, {"two_effect_trials", r.two_effect_trials},
              {"two_effect_both_named", r.two_effect_both}, {"channel_trials", r.channel_trials},
              {"channel_right", r.channel_right}, {"below_threshold", r.below_threshold},
              {"outside_trials", r.outside_trials}, {"outside_located", r.outside_located},
              {"outside_below_model_error", r.outside_below_model_error},
              {"seconds", r.seconds}, {"trials", trials}};
}

}  // namespace canalsim::diagnosis
