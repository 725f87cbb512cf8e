#include "calibration/calibrate.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>

#include "calibration/fits.hpp"
#include "calibration/grid_check.hpp"
#include "calibration/levenberg_marquardt.hpp"
#include "calibration/time_offset.hpp"
#include "calibration/warning_once.hpp"
#include "calibration/written_model.hpp"
#include "calibration/problem.hpp"
#include "calibration/starts.hpp"
#include "calibration/statistics.hpp"
#include "core/errors.hpp"
#include "core/format.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::calibration {
namespace {

using scenarios::Scenario;

// A weighted cost per sample above this leaves more than a fifth of the channels' spread
// unexplained (residual RMS > 22 % of it): a fit that may sit in the wrong basin. Measured fits of
// truths the model cannot represent exactly end at 0.027-0.040 (1.5x and 2x the cells, another
// limiter), 0.083 on 4x the cells, where a second start moved Cd submerged by 10 %.
constexpr double kDoubtfulCost = 0.05;

// Refine when twice the cells lower the cost at the optimum by more than a third. On a truth
// that another simulator made on a fine grid (docs/calibration.md, "Grid refinement") the lab's
// 100 cells leave 0.36 of the cost on 200, 200 cells 0.41 on 400, and 400 cells 1.08 on 800.
constexpr double kRefineBelow = 2.0 / 3.0;

// Whether the k-th grid's calibration (k = 0: the scenario's), with this grid check and fitted
// cost, is calibrated again on twice the cells (`coarser_cost`: the fit on the grid before, k > 0).
// The grid check re-simulates the optimum, whose parameters absorbed part of the grid's error:
// after a refinement that paid, a further one is tried even when the check alone would not ask
// for it (a refinement that does not lower the cost is dropped).
bool refinement_pays(const GridCheck& grid, double cost, int k, double coarser_cost) {
  const bool check_asks = grid.refined_cost < kRefineBelow * grid.cost;
  const bool last_paid = k > 0 && cost < kRefineBelow * coarser_cost;
  return grid.done && (check_asks || last_paid);
}

// Whether a calibration with this grid check and fitted cost will be followed by one on twice the
// cells (refinement_pays for its round); empty when none can follow. A calibration that will be
// leaves its numerical uncertainty and validation to the refined one.
using RefinementFollows = std::function<bool(const GridCheck& grid, double cost_after)>;

// What one grid's calibration hands to the refined one: the simulations of its optimum on twice
// the cells (before the sensors), which its grid check made and where the refined one starts.
struct Handover {
  std::vector<Channels> twice_the_cells;
};

// Whether the first run's large cost is the grid's: twice the cells bring it below kDoubtfulCost,
// and by enough that the grid will be refined. Another start on this grid would then search for
// a basin the refined grid explains: on four lab recordings of an 800-cell truth the 100-cell fit
// ends at 0.095 (0.033 on twice the cells), and a second start took the 100-cell pass from 116 to
// 348 simulations to find the same optimum 0.17 % lower. One simulation per recording on twice the
// cells; a failing one leaves the doubt.
bool cost_is_the_grids(ReplayProblem& problem, TwiceTheCells& twice, const Run& run) {
  try {
    const double refined = cost_per_sample(problem.residuals(twice.observed_at(run.z)));
    return refined < kDoubtfulCost && refined < kRefineBelow * run.cost;
  } catch (const std::exception&) {
    return false;
  }
}

// Why the first run's optimum is doubtful, empty when it is not: not converged or a large cost
// (unless a grid refinement will follow that explains the cost: it continues the run from there),
// a parameter at a bound (but the published law's, Parameter::low_is_published), a parameter not
// determined or barely moving the recordings. Costs no simulation but the grid's: the Jacobian at
// the run's last point is the one Levenberg–Marquardt took there. Measured on the benchmark's
// clean 800-cell truth (bench/README.md, truth:1): a 100-cell run that stops at its 30 iterations
// still creeping along the discharge coefficients' valley and starts again there takes the
// calibration to 1260 simulations against 716 when the refined grids continue the first run,
// and both reach the same optimum.
std::string doubt(ReplayProblem& problem, TwiceTheCells& twice, const Run& run, bool refinable) {
  const auto& params = problem.parameters();
  if (!std::isfinite(run.cost)) return "the first run found no usable solution";
  std::optional<bool> grids;  // whether the grid explains the cost (one simulation per recording)
  const auto the_grids = [&] {
    if (!grids) grids = refinable && cost_is_the_grids(problem, twice, run);
    return *grids;
  };
  if (!run.converged && !the_grids()) return "the first run did not converge";
  std::set<std::string> at_the_published_law;  // resting at a low_is_published bound: an answer
  for (std::size_t j = 0; j < params.size(); ++j) {
    const double lo = params[j].to_search(params[j].low), hi = params[j].to_search(params[j].high);
    const bool at_low = run.z[j] <= lo + 1e-6 * (hi - lo);
    if (at_low && params[j].low_is_published) {
      at_the_published_law.insert(params[j].name);
      continue;
    }
    if (at_low || run.z[j] >= hi - 1e-6 * (hi - lo)) return params[j].name + " ended at a bound";
  }
  if (run.cost > kDoubtfulCost && !the_grids()) {
    return "its cost " + format_g(run.cost, 3) + " is above " + format_g(kDoubtfulCost, 2);
  }
  const std::vector<Channels> at = problem.predict(run.z);
  const std::vector<double> r = problem.residuals(at);
  const ParameterStatistics stats =
      parameter_statistics(params, run.z, problem.jacobian(run.z, r), r, problem.residual_series(at));
  for (const auto& u : stats.unidentified) {
    // A strongly correlated pair is named in the result, but another start cannot separate it:
    // on the lab recordings Cd free and Cd submerged correlate at 0.97 and the second start found
    // the same optimum to six digits at twice the simulations. Undetermined parameters and those
    // the recordings barely move are doubtful.
    if (u.reason.rfind("|correlation|", 0) == 0) continue;
    if (std::all_of(u.parameters.begin(), u.parameters.end(),
                    [&](const std::string& n) { return at_the_published_law.count(n) > 0; })) {
      continue;  // a regularisation of 0 has no relative std
    }
    std::string names;
    for (const auto& n : u.parameters) names += (names.empty() ? "" : ", ") + n;
    return names + " not identifiable (" + u.reason + ")";
  }
  return "";
}

// Recordings of another canal: a `scenario` metadata line naming another canal, or levels the
// canal's walls could not hold. One line per recording, naming it and the difference.
std::vector<std::string> other_canal_problems(const Scenario& s, const std::vector<Recording>& recordings) {
  std::vector<std::string> problems;
  const double wall_mm = (s.pools.empty() ? 1e9 : s.pools.back().wall_height_m) * 1e3;
  for (const Recording& rec : recordings) {
    const std::string name = rec.source.empty() ? "recording" : rec.source;
    const std::string canal = rec.meta("scenario");
    if (!canal.empty() && canal != s.name) {
      problems.push_back(name + ": recorded on canal '" + canal + "', but the scenario is '" + s.name +
                         "' (# scenario: metadata)");
      continue;
    }
    for (const char* c : {columns::level_downstream_end, columns::level_below_gate}) {
      if (!rec.has(c)) continue;
      const auto [lo, hi] = std::minmax_element(rec.column(c).begin(), rec.column(c).end());
      if (*lo < -1.0 || *hi > wall_mm) {
        problems.push_back(name + ": " + c + " spans " + format_g(*lo, 4) + ".." + format_g(*hi, 4) +
                           " mm, outside the " + format_g(wall_mm, 4) + " mm walls of " + s.name +
                           ": not a recording of this canal");
        break;
      }
    }
  }
  return problems;
}

}  // namespace

ReplayOptions CalibrateOptions::default_replay() {
  ReplayOptions r;
  // The gate position is left out: no default parameter acts on it, and a simulated one is
  // interpolated between solver steps across the command's jumps (a simulator's artefact).
  r.channels = {columns::level_downstream_end, columns::level_below_gate, columns::upstream_level, columns::discharge};
  r.use_recorded_upstream = true;
  r.clock_with_upstream = true;
  r.start_at_recorded_level = true;
  r.fit_fraction = 1.0;
  r.warmup_s = 0.0;
  return r;
}

Status CalibrateOptions::validate() const {
  return Validator()
      .require(starts >= 1 && starts <= 10, "starts", starts, "1..10")
      .require(screened_points >= 0 && screened_points <= 1000, "screened_points", screened_points, "0..1000")
      .require(max_iterations >= 1 && max_iterations <= 500, "max_iterations", max_iterations, "1..500")
      .require(threads >= 1 && threads <= 64, "threads", threads, "1..64")
      .require(replay.fit_fraction > 0.0 && replay.fit_fraction <= 1.0, "replay.fit_fraction", replay.fit_fraction,
               "(0, 1]")
      .require(replay.warmup_s >= 0.0, "replay.warmup_s", replay.warmup_s, ">= 0")
      .require(std::set<scenarios::GateLaw>(gate_laws.begin(), gate_laws.end()).size() == gate_laws.size(), "gate_laws",
               "each law at most once")
      .require(grid_refinements >= 0 && grid_refinements <= 3, "grid_refinements", grid_refinements, "0..3")
      .status();
}

namespace {

// The replay of a calibration of `parameters`: the actuator speed shows in the gate position, so
// that is compared when the speed is fitted.
ReplayOptions replay_for(const std::vector<Parameter>& parameters, const CalibrateOptions& o) {
  ReplayOptions replay = o.replay;
  const bool speed = std::any_of(parameters.begin(), parameters.end(), [](const Parameter& p) { return p.name == "actuator_speed_mm_s"; });
  if (speed && std::find(replay.channels.begin(), replay.channels.end(), columns::gate_position) == replay.channels.end()) {
    replay.channels.push_back(columns::gate_position);
  }
  return replay;
}

// Whether a refinement follows a run that ended at `run`: `follows` on the grid check there. A
// simulation that fails on twice the cells says no (the grid check at the optimum decides again).
bool refinement_follows(ReplayProblem& fit, TwiceTheCells& twice, const Run& run, const RefinementFollows& follows) {
  try {
    const std::vector<Channels> at = fit.predict(run.z);
    const double cost = cost_per_sample(fit.residuals(at));
    return follows(grid_check(fit, twice.observed_at(run.z), at, cost), cost);
  } catch (const std::exception&) {
    return false;
  }
}

// The first run from the scenario's values, precisely. A grid that may be refined scouts first:
// when twice the cells lower the cost at the scout's end by enough that the refinement follows,
// the refined grid continues from there (its optimum moves by more than this one's last precise
// iterations would). Measured on the benchmark's truth:1 (bench/README.md), a 100-cell run to
// the precise tolerance takes 27 iterations (488 simulations) to gain 5.6 % after its third, and
// the refined grids cut the cost 12-fold; the scout stops after 13 (docs/calibration.md, "The
// first grid scouts").
Run first_run(ReplayProblem& fit, TwiceTheCells& twice, const std::vector<double>& z0, const CalibrateOptions& o,
              const RefinementFollows& follows, bool on_refined_grid, Calibration& c) {
  const int runs = o.starts;
  const double tolerance = on_refined_grid ? kRefinedGridTolerance : kPreciseTolerance;
  const bool scouted = o.grid_check && static_cast<bool>(follows) && !on_refined_grid;
  Run best = levenberg_marquardt(fit, z0, o.max_iterations, o.progress, 0, runs, scouted ? kScoutTolerance : tolerance,
                                 /*secant=*/on_refined_grid);
  c.iterations += best.iterations;
  const bool refinement_likely = scouted && std::isfinite(best.cost) && refinement_follows(fit, twice, best, follows);
  if (!refinement_likely && std::isfinite(best.cost) && (scouted || (on_refined_grid && !fit.differenced_at(best.z)))) {
    // Continued precisely, or, on a refined grid, which starts near its optimum (the coarser
    // grid's) and simulates at 4x the cost, where secant Jacobians carried the run: ended with
    // Jacobians by differences, so that its stopping rules and statistics see the true Jacobian.
    const int left = scouted ? o.max_iterations - best.iterations : o.max_iterations;
    Run finished = levenberg_marquardt(fit, best.z, left, o.progress, 0, runs, tolerance);
    c.iterations += finished.iterations;
    if (finished.cost <= best.cost) best = std::move(finished);
  }
  return best;
}

// The starts after the first (the best of points screened over the bounds): run when the first
// optimum is doubtful, or always without further_starts_only_when_doubtful; each scouts with a
// loose tolerance and is continued precisely only when it ends below the best so far (it mostly
// finds the same optimum, and its tail iterations cost a simulation per hydraulic parameter and
// recording each). Says in c.starts_note why they ran or did not, and counts them in c.starts.
void run_further_starts(ReplayProblem& fit, TwiceTheCells& twice, const std::vector<double>& z0,
                        const CalibrateOptions& o, const RefinementFollows& follows, Run& best, Calibration& c) {
  std::vector<Run> starts{Run{z0, c.cost_before, 0, "", false}};
  if (o.starts > 1) {
    const std::string why = doubt(fit, twice, best, static_cast<bool>(follows));
    if (!o.further_starts_only_when_doubtful || !why.empty()) {
      c.starts_note = why.empty() ? "every start run (further_starts_only_when_doubtful off)"
                                  : "further starts run: " + why;
      if (o.progress) o.progress({0.5, "screening " + std::to_string(o.screened_points) + " points over the bounds"});
      std::vector<Run> screened = screened_starts(fit, o.screened_points);
      for (std::size_t k = 0; k < screened.size() && static_cast<int>(starts.size()) < o.starts; ++k) starts.push_back(screened[k]);
    } else {
      const std::string grids = " (the grid's: twice the cells bring it below " + format_g(kDoubtfulCost, 2) + ")";
      c.starts_note = best.converged
                          ? "one start: the first optimum converged inside the bounds, every parameter determined, at cost " +
                                format_g(best.cost, 3) + (best.cost > kDoubtfulCost ? grids : "")
                          : "one start: the first run stopped at its iteration limit at cost " + format_g(best.cost, 3) +
                                grids + "; the refined grid continues it";
    }
  }
  for (std::size_t k = 1; k < starts.size(); ++k) {
    const int run = static_cast<int>(k);
    Run r = levenberg_marquardt(fit, starts[k].z, o.max_iterations, o.progress, run, o.starts, kScoutTolerance);
    c.iterations += r.iterations;
    if (r.cost < best.cost) {
      r = levenberg_marquardt(fit, r.z, o.max_iterations, o.progress, run, o.starts, kPreciseTolerance);
      c.iterations += r.iterations;
    }
    if (r.cost < best.cost) best = std::move(r);
  }
  c.starts = static_cast<int>(starts.size());
}

// How sure the estimates at the optimum are: the statistical part (parameter_statistics), the
// numerical part (re-estimates on other numerics, discretisation.hpp) and the grid-converged
// estimates. A grid that will be refined leaves all of it to the refined one (its estimates are
// only that one's start): no Jacobian at its optimum, zero spreads.
struct Uncertainty {
  std::vector<double> values, converged, numerical;
  ParameterStatistics stats;
};

Uncertainty uncertainty_at(ReplayProblem& fit, TwiceTheCells& twice, const Run& best,
                           const std::vector<Channels>& optimum, const std::vector<double>& r, bool refined_next,
                           const CalibrateOptions& o, Calibration& c) {
  const std::vector<Parameter>& parameters = fit.parameters();
  Uncertainty u;
  for (std::size_t j = 0; j < parameters.size(); ++j) u.values.push_back(parameters[j].from_search(best.z[j]));
  u.converged = u.values;
  u.numerical.assign(parameters.size(), 0.0);
  u.stats.std.assign(parameters.size(), 0.0);
  u.stats.sensitivity.assign(parameters.size(), 0.0);
  if (refined_next) return u;
  if (o.progress) o.progress({0.91, "statistics at the optimum"});
  const std::vector<double> J = fit.jacobian(best.z, r);
  u.stats = parameter_statistics(parameters, best.z, J, r, fit.residual_series(optimum));
  c.inflation = u.stats.inflation;
  c.correlation = u.stats.correlation;
  for (const auto& unidentified : u.stats.unidentified) {
    c.identifiability.push_back({unidentified.parameters, unidentified.reason, unidentified.determined});
  }
  if (o.grid_check) {
    // The numerical uncertainty: how far the estimates move on other numerics (discretisation.hpp).
    if (o.progress) o.progress({0.92, "numerical uncertainty: re-estimates on other numerics"});
    c.discretisation = discretisation_shifts(fit, best.z, J, 2, &twice.observed_at(best.z));
    u.numerical = numerical_uncertainty(c.discretisation, parameters.size());
    u.converged = grid_converged(parameters, u.values, c.discretisation);
    for (auto& d : c.discretisation) d.at_optimum.clear();  // the result stays light (diagnosis keeps dozens)
  }
  return u;
}

// Each parameter's estimate: its value, the statistical and numerical spreads combined in
// quadrature, the grid-converged value, and whether it rests at a bound.
std::vector<ParameterEstimate> estimates(const std::vector<Parameter>& parameters, const Scenario& scenario,
                                         const std::vector<double>& z, const Uncertainty& u) {
  std::vector<ParameterEstimate> out;
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    const Parameter& p = parameters[j];
    const double grid = u.numerical[j];
    const double statistical = u.stats.std[j];
    ParameterEstimate e{p.name, p.unit, p.key, p.key_scale, p.get(scenario), u.values[j],
                        std::sqrt(statistical * statistical + grid * grid), statistical, grid, u.converged[j],
                        p.low, p.high, false, u.stats.sensitivity[j]};
    const double span = p.to_search(p.high) - p.to_search(p.low);
    e.at_bound = z[j] <= p.to_search(p.low) + 1e-6 * span || z[j] >= p.to_search(p.high) - 1e-6 * span;
    out.push_back(e);
  }
  return out;
}

// One calibration of the scenario's parameters named by `specs` (the recordings checked): the
// nominal replay, the first run, further starts when it is doubtful, the grid check at the
// optimum, the uncertainty of the estimates, and the fits before and after, on the validation
// recordings too.
Calibration calibrate_with(const Scenario& scenario, const std::vector<Recording>& recordings,
                           const std::vector<Recording>& validation, const std::vector<std::string>& specs,
                           const CalibrateOptions& o, const RefinementFollows& follows = {},
                           const Handover* from_coarser = nullptr, Handover* to_finer = nullptr) {
  std::vector<Parameter> parameters = select_parameters(scenario, specs);
  const auto started = std::chrono::steady_clock::now();
  Calibration c;
  c.calibrated = scenario;
  ReplayOptions replay = replay_for(parameters, o);
  WarningOncePerRecording warn_once(o.replay.warning);
  replay.warning = [&warn_once](const std::string& message) { warn_once(message); };
  ReplayProblem fit(scenario, parameters, recordings, replay, o.threads);
  if (from_coarser) fit.prime_start(from_coarser->twice_the_cells);
  c.samples = fit.residual_count();
  if (o.progress) o.progress({0.0, "nominal replay of " + std::to_string(recordings.size()) + " recording(s)"});
  try {
    const std::vector<double> z0 = fit.start();
    const std::vector<Channels> nominal = fit.predict(z0);
    c.cost_before = cost_per_sample(fit.residuals(nominal));
    TwiceTheCells twice(fit);
    // A refined grid starts from the coarser grid's estimates, past any scan.
    const std::vector<double> z_start = from_coarser ? z0 : start_at_the_scans(fit, z0, c.cost_before, o.progress, c.scan_note);
    Run best = first_run(fit, twice, z_start, o, follows, from_coarser != nullptr, c);
    run_further_starts(fit, twice, z_start, o, follows, best, c);
    if (!std::isfinite(best.cost)) throw std::runtime_error("no start converged to a usable solution");
    const std::vector<Channels> optimum = fit.predict(best.z);
    const std::vector<double> r = fit.residuals(optimum);
    c.cost_after = cost_per_sample(r);
    c.solver_report = best.report;
    bool refined_next = false;  // a calibration on twice the cells follows and replaces this one
    if (o.grid_check) {
      if (o.progress) o.progress({0.9, "grid check: the optimum on twice the cells"});
      c.grid = grid_check(fit, twice.observed_at(best.z), optimum, c.cost_after);
      refined_next = follows && follows(c.grid, c.cost_after);
      if (refined_next && to_finer) to_finer->twice_the_cells = twice.truth_at(best.z);
    }
    const Uncertainty u = uncertainty_at(fit, twice, best, optimum, r, refined_next, o, c);
    c.parameters = estimates(parameters, scenario, best.z, u);
    c.calibrated = fit.scenario_at(best.z);
    add_fits(fit, nominal, optimum, false, c);
    if (!validation.empty() && !refined_next) {
      if (o.progress) o.progress({0.93, "validation recordings"});
      ReplayProblem check(scenario, parameters, validation, replay, o.threads, &fit.weights());
      add_fits(check, check.predict(check.start()), check.predict(best.z), true, c);
      c.simulations += check.simulations();
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    c.ok = false;
    c.message = e.what();
  }
  c.simulations += fit.simulations();
  c.warnings = warn_once.kept();
  c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (o.progress) o.progress({1.0, "done"});
  return c;
}

// The "before" figures of `c` — cost, RMS and Nrmse per recording and channel, the nominal
// series — replaced by those of `given`, the scenario as the user gave it (c was calibrated on
// it with another gate law).
void restate_before(Calibration& c, const Scenario& given, const std::vector<std::string>& specs,
                    const std::vector<Recording>& recordings, const std::vector<Recording>& validation,
                    const CalibrateOptions& o) {
  const std::vector<Parameter> parameters = select_parameters(given, specs);
  const ReplayOptions replay = replay_for(parameters, o);
  const auto restate = [&c](ReplayProblem& problem, bool validation_set) {
    const std::vector<Channels> nominal = problem.predict(problem.start());
    restate_fits(problem, nominal, validation_set, FitSide::before, c);
    c.simulations += problem.simulations();
    return nominal;
  };
  ReplayProblem fit(given, parameters, recordings, replay, o.threads);
  c.cost_before = cost_per_sample(fit.residuals(restate(fit, false)));
  if (!validation.empty()) {
    ReplayProblem check(given, parameters, validation, replay, o.threads, &fit.weights());
    restate(check, true);
  }
}

// CalibrateOptions::gate_laws: one calibration per law, the lowest cost kept.
Calibration compare_gate_laws(const Scenario& scenario, const std::vector<Recording>& recordings,
                              const std::vector<Recording>& validation, const std::vector<std::string>& specs,
                              const CalibrateOptions& o, const RefinementFollows& follows) {
  const auto started = std::chrono::steady_clock::now();
  const std::size_t n = o.gate_laws.size();
  Calibration best;
  best.ok = false;
  std::vector<GateLawFit> laws;
  int simulations = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const scenarios::GateLaw law = o.gate_laws[k];
    const Scenario with_law = scenarios::with_gate_law(scenario, law);
    CalibrateOptions one = o;
    if (o.progress) {
      one.progress = [&o, k, n, law](const ProgressReport& p) {
        o.progress({(static_cast<double>(k) + std::max(p.fraction, 0.0)) / static_cast<double>(n),
                    std::string("gate law ") + scenarios::to_string(law) + ": " + p.message});
      };
    }
    Calibration c = calibrate_with(with_law, recordings, validation, specs, one, follows);
    simulations += c.simulations;
    laws.push_back({law, c.ok, c.cost_after, c.message, false});
    if (c.ok && (!best.ok || c.cost_after < best.cost_after)) {
      best = std::move(c);
      for (auto& l : laws) l.kept = false;
      laws.back().kept = true;
    } else if (!best.ok && best.message.empty()) {
      best.message = std::string("gate law ") + scenarios::to_string(law) + ": " + c.message;
    }
  }
  best.simulations = simulations;
  // The kept law's "before" figures are the scenario's own when every gate already had that law.
  bool kept_is_given = best.ok;
  for (const auto& l : laws) {
    if (!l.kept) continue;
    scenarios::for_each_sluice_gate(scenario, [&](const std::string&, const scenarios::GateSpec& g) {
      kept_is_given = kept_is_given && g.law == l.law;
    });
  }
  if (best.ok && !kept_is_given) {
    try {
      restate_before(best, scenario, specs, recordings, validation, o);
    } catch (const std::exception& e) {
      best.warnings.push_back(std::string("the scenario as given could not be replayed (") + e.what() +
                              "): the figures before are those of the kept gate law at the start");
    }
  }
  best.gate_laws = std::move(laws);
  best.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return best;
}

// The cells of every pool.
std::vector<int> cells_of(const Scenario& s) {
  std::vector<int> cells;
  for (const auto& p : s.pools) cells.push_back(p.cells);
  return cells;
}

// Why `c`, the k-th grid's calibration, is not refined further (refinement_pays); empty when it is.
std::string why_not_refine(const Calibration& c, int k, double coarser_cost) {
  if (!c.ok || !c.grid.done) return "no refinement: the grid check did not run";
  if (refinement_pays(c.grid, c.cost_after, k, coarser_cost)) return "";
  return "refinement stopped: twice the cells change the cost by " +
         format_fixed(100.0 * (c.grid.refined_cost / c.grid.cost - 1.0), 1) +
         " % (it refines while they lower it by more than a third, or the last refinement did)";
}

// What calibrate_with is told of the refinement after round k (null after the last allowed one).
RefinementFollows follows_round(int k, double coarser_cost, const CalibrateOptions& o) {
  if (!o.grid_check || k >= o.grid_refinements) return {};
  return [k, coarser_cost](const GridCheck& grid, double cost) { return refinement_pays(grid, cost, k, coarser_cost); };
}

// `later`, a calibration made after `earlier` (on twice its cells, or on the same grid to complete
// it), takes over what `earlier` carried: the starts of the parameters, the starts run on the
// scenario's grid, the gate laws compared, the time offset found, the grids so far, the
// iterations and warnings.
void carry_over(Calibration& later, Calibration&& earlier) {
  for (std::size_t j = 0; j < later.parameters.size(); ++j) later.parameters[j].start = earlier.parameters[j].start;
  later.starts = earlier.starts;
  later.starts_note = std::move(earlier.starts_note);
  later.scan_note = std::move(earlier.scan_note);
  later.gate_laws = std::move(earlier.gate_laws);
  later.time_offset_note = std::move(earlier.time_offset_note);
  std::vector<std::vector<int>> grids = std::move(earlier.grids);
  if (grids.empty() || grids.back() != cells_of(later.calibrated)) grids.push_back(cells_of(later.calibrated));
  later.grids = std::move(grids);
  later.iterations += earlier.iterations;
  later.warnings.insert(later.warnings.begin(), earlier.warnings.begin(), earlier.warnings.end());
}

// One more calibration on the grid of `c` (from its estimates, one start) or on twice its cells,
// with every statistic unless `follows` says a refinement will follow.
Calibration calibrate_again(const Calibration& c, bool on_twice_the_cells, const std::vector<Recording>& recordings,
                            const std::vector<Recording>& validation, const std::vector<std::string>& specs,
                            const CalibrateOptions& o, const std::string& stage, const RefinementFollows& follows,
                            const Handover* from_coarser = nullptr, Handover* to_finer = nullptr) {
  const Scenario scenario = on_twice_the_cells ? scenarios::with_cells_multiplied(c.calibrated, 2) : c.calibrated;
  CalibrateOptions one = o;
  one.starts = 1;  // from the estimates, which the coarser grid placed
  if (o.progress) {
    one.progress = [&o, stage](const ProgressReport& p) { o.progress({std::max(p.fraction, 0.0), stage + ": " + p.message}); };
  }
  return calibrate_with(scenario, recordings, validation, specs, one, follows, from_coarser, to_finer);
}

// CalibrateOptions::grid_refinements: `c` calibrated again on twice the cells, from its estimates,
// while that pays; the "before" figures restated for the scenario as given. `c` and every round
// but the last were calibrated knowing a refinement would follow (follows_round), so their
// numerical uncertainty and validation were left to it: a round whose refinement is dropped is
// completed on its own grid.
Calibration refine_grid(Calibration c, Handover handover, const Scenario& given, const std::vector<Recording>& recordings,
                        const std::vector<Recording>& validation, const std::vector<std::string>& specs,
                        const CalibrateOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  const double first_seconds = c.seconds;
  c.grids = {cells_of(c.calibrated)};
  int simulations = c.simulations;
  double coarser_cost = 0.0;  // the fit on the grid before (k > 0)
  bool calibrated_again = false;  // the "before" figures are then those of c's own start
  for (int k = 0; k < o.grid_refinements; ++k) {
    if (std::string why = why_not_refine(c, k, coarser_cost); !why.empty()) {
      c.grid_note = std::move(why);
      break;
    }
    const int cells = 2 * c.calibrated.pools.front().cells;
    Handover to_finer;
    Calibration next = calibrate_again(c, true, recordings, validation, specs, o, "grid refinement " + std::to_string(k + 1),
                                       follows_round(k + 1, c.cost_after, o), &handover, &to_finer);
    handover = std::move(to_finer);
    calibrated_again = true;
    simulations += next.simulations;
    if (!next.ok || !(next.cost_after < c.cost_after)) {
      const std::string note = "refinement to " + std::to_string(cells) + " cells dropped: " +
                               (next.ok ? "the cost did not fall (" + format_g(next.cost_after, 3) + ")" : next.message);
      Calibration complete = calibrate_again(c, false, recordings, validation, specs, o, "statistics", {});
      simulations += complete.simulations;
      carry_over(complete, std::move(c));
      c = std::move(complete);
      c.grid_note = note;
      break;
    }
    coarser_cost = c.cost_after;
    carry_over(next, std::move(c));
    c = std::move(next);
    c.grid_note = "refined " + std::to_string(k + 1) + " time(s): the grid limited the fit";
    if (k + 1 == o.grid_refinements) {
      c.grid_note += "; the most allowed (the last lowered the cost by " +
                     format_fixed(100.0 * (1.0 - c.cost_after / coarser_cost), 1) + " %)";
    }
  }
  c.simulations = simulations;
  if (calibrated_again) {
    try {
      restate_before(c, given, specs, recordings, validation, o);
    } catch (const std::exception& e) {
      c.warnings.push_back(std::string("the scenario as given could not be replayed (") + e.what() +
                           "): the figures before are those of the refined grid at the start");
    }
  }
  c.seconds = first_seconds + std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return c;
}

// The scan of time_offset.hpp at the first fit's estimates, when it applies: the parameters do not
// hold the delay already, no gate laws are compared, the scenario's own delay leaves the scan's
// ±2 s within the parameter's bounds, and the scan's simulations succeed.
std::optional<TimeOffsetScan> scan_after_first_fit(Calibration& c, const Scenario& given, const std::vector<Recording>& recordings,
                                                   const std::vector<std::string>& specs, const CalibrateOptions& o) {
  const bool named = std::any_of(specs.begin(), specs.end(), [](const std::string& s) { return s.substr(0, s.find(':')) == "sensor_delay_s"; });
  if (!c.ok || named || !o.gate_laws.empty() || std::abs(given.sensors.delay_s) > 8.0) return std::nullopt;
  if (o.progress) o.progress({1.0, "scanning a time offset between the command and the levels"});
  ReplayOptions quiet = replay_for(select_parameters(given, specs), o);  // (the estimates may sit on a bound)
  quiet.warning = [](const std::string&) {};  // the first fit passed them on
  try {
    const TimeOffsetScan scan = scan_time_offset(c.calibrated, recordings, quiet, o.threads);
    c.simulations += static_cast<int>(recordings.size());
    return scan;
  } catch (const std::exception&) {
    return std::nullopt;  // the first fit's optimum replayed before: not for a delay to decide
  }
}

// A time offset between command and levels (time_offset.hpp), looked for after the first fit.
// Found where the default set is fitted, the calibration runs again from the first fit's
// estimates with `sensor_delay_s` added (one start; "before" figures and starts those of the
// scenario as given); where the user named the parameters, the note says what to add.
Calibration fit_time_offset(Calibration c, const Scenario& given, const std::vector<Recording>& recordings,
                            const std::vector<Recording>& validation, std::vector<std::string>& specs,
                            const CalibrateOptions& o, const RefinementFollows& follows, Handover& handover) {
  const std::optional<TimeOffsetScan> scan = scan_after_first_fit(c, given, recordings, specs, o);
  if (!scan || !scan->worth_fitting()) return c;
  const std::string found = "the levels " + std::string(scan->delay_s > 0.0 ? "lag" : "lead") + " the command by about " +
                            format_g(std::abs(scan->delay_s), 2) + " s (after the first fit a delay of the level sensors of " +
                            format_g(scan->delay_s, 3) + " s explains " +
                            format_fixed(100.0 * (1.0 - scan->cost_at_best / scan->cost_at_zero), 0) + " % of the cost left)";
  const bool default_set = o.parameters.empty() ||
                           std::all_of(o.parameters.begin(), o.parameters.end(), [](const std::string& p) { return p.rfind('+', 0) == 0; });
  if (!default_set) {
    c.time_offset_note = found + "; not fitted: the parameters were named (add sensor_delay_s to fit it)";
    return c;
  }
  specs.push_back("sensor_delay_s");
  Scenario from = c.calibrated;
  from.sensors.delay_s = scan->delay_s;
  CalibrateOptions one = o;
  one.starts = 1;  // from the first fit's estimates
  Handover to_finer;  // replaces the first fit's only if this one succeeds
  Calibration again = calibrate_with(from, recordings, validation, specs, one, follows, nullptr, &to_finer);
  if (!again.ok) {
    specs.pop_back();
    c.time_offset_note = found + "; not fitted: the calibration with it failed (" + again.message + ")";
    return c;
  }
  handover = std::move(to_finer);
  restate_before(again, given, specs, recordings, validation, o);
  for (std::size_t j = 0; j < c.parameters.size(); ++j) again.parameters[j].start = c.parameters[j].start;
  again.parameters.back().start = given.sensors.delay_s;
  again.starts = c.starts;
  again.starts_note = c.starts_note;
  again.scan_note = c.scan_note;
  again.time_offset_note = found + "; sensor_delay_s fitted with the default set (its estimate in the table)";
  again.simulations += c.simulations;
  again.iterations += c.iterations;
  again.seconds += c.seconds;
  again.warnings.insert(again.warnings.begin(), c.warnings.begin(), c.warnings.end());
  return again;
}

}  // namespace

Calibration calibrate(const Scenario& scenario, const std::vector<Recording>& recordings,
                      const std::vector<Recording>& validation, const CalibrateOptions& o) {
  if (const Status status = o.validate(); !status) throw InputError("calibrate options: " + status.message());
  std::vector<Recording> all = recordings;
  all.insert(all.end(), validation.begin(), validation.end());
  std::vector<std::string> problems = check_recordings(scenario, all);
  for (auto& p : other_canal_problems(scenario, all)) problems.push_back(std::move(p));
  if (!problems.empty()) {
    std::string line;
    for (const auto& p : problems) line += (line.empty() ? "" : "; ") + p;
    throw InputError(line);
  }
  if (recordings.empty()) throw InputError("no recordings to calibrate on");
  if (!o.gate_laws.empty() && !scenarios::has_sluice_gate(scenario)) {
    throw InputError("gate laws to compare, but scenario " + scenario.source + " has no sluice gate");
  }
  const bool replayed = o.replay.use_recorded_upstream && recordings.front().has(columns::upstream_level);
  std::vector<std::string> specs = chosen_parameters(o.parameters, default_parameters(scenario, recordings, replayed));
  select_parameters(scenario, specs);  // bad specs: one line before any work
  const RefinementFollows follows = follows_round(0, 0.0, o);
  Handover handover;  // with gate laws compared, the refined grid simulates its start itself
  Calibration c = o.gate_laws.empty() ? calibrate_with(scenario, recordings, validation, specs, o, follows, nullptr, &handover)
                                      : compare_gate_laws(scenario, recordings, validation, specs, o, follows);
  c = fit_time_offset(std::move(c), scenario, recordings, validation, specs, o, follows, handover);
  if (o.grid_refinements > 0) c = refine_grid(std::move(c), std::move(handover), scenario, recordings, validation, specs, o);
  if (o.write_grid_converged && c.ok && c.grid.done) {
    std::vector<std::string> fitted;  // the time offset's refit may have added sensor_delay_s
    for (const auto& p : c.parameters) fitted.push_back(p.name + ":" + format_g(p.low, 17) + ":" + format_g(p.high, 17));
    const std::vector<Parameter> parameters = select_parameters(c.calibrated, fitted);
    write_grid_converged(c, parameters, recordings, validation, replay_for(parameters, o), o.threads);
  }
  if (c.ok) c.breakdown = residual_breakdown(c.series);
  if (o.try_model_forms && c.ok) {
    try {
      c.model_forms = compare_model_forms(scenario, c, recordings, validation, o);
    } catch (const std::exception& e) {
      c.model_forms.message = std::string("the model-form choices could not be refitted: ") + e.what();
    }
  }
  return c;
}

}  // namespace canalsim::calibration
