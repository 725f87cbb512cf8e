#include "scenarios/settle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/format.hpp"
#include "scenarios/run_cost.hpp"
#include "solver/steady_state.hpp"

namespace canalsim::scenarios {
namespace {

constexpr double kMm = 1e-3;
constexpr double kSettledDepth = 1e-6;      // m, per chunk of marching (settled)
constexpr double kSettledDischarge = 1e-6;  // of the largest discharge, per chunk
constexpr int kMarchingChunks = 20;         // of a march that settles the canal
// Of the largest discharge, per chunk, for a stalled Newton: settled()'s depth criterion relative
// to the lab's ~50 mm depths (2e-5), halved. kSettledDischarge is twenty times stricter than that,
// and stalls whose depths are steady to 1/100 of kSettledDepth exceed it by 1.1-1.9 times.
constexpr double kStalledDischarge = 1e-5;

// Newton failed: the experiment starts from `marching` seconds of time marching instead. Never
// silent — an error when the caller requires the steady state, else a warning naming the
// opening held and the levels reached (first and last cell of every pool).
void warn_marched_start(const BuiltCanal& b, const Scenario& s, const ExperimentSpec& e, const SimulateOptions& options,
                        const std::string& failure, double marching) {
  const std::string what = s.source + ": experiment " + e.name + ": the steady state (Newton) failed (" + failure + ")";
  if (options.require_steady_state) throw std::runtime_error(what);
  std::string state = "the gate held at " + format_g(b.controlled->opening(-1e-9) / kMm) + " mm, levels";
  for (int r = 0; r < b.canal.reach_count(); ++r) {
    const auto& reach = b.canal.reach(r);
    state += (r ? "; " : " ") + format_g(reach.level(0) / kMm) + " .. " +
             format_g(reach.level(reach.cells() - 1) / kMm) + " mm";
  }
  warn(options, what + "; it starts after " + format_g(marching) + " s of time marching instead, from " + state);
}

// Steps to `t_end` (no probes: what advance_to does) with the run's cost guard after each step.
void march_to(solver::Canal& canal, double t_end, RunCostGuard& guard, const std::string& what) {
  while (canal.time() < t_end) {
    const double before = canal.time();
    if (const solver::Status status = canal.step(t_end - before); !status) {
      throw std::runtime_error(what + ": " + status.message());
    }
    guard.check(canal.statistics().steps, canal.time(), canal.time() - before);
  }
}

// The state time marching settles: the depth and discharge of every cell of every pool.
struct MarchedState {
  std::vector<double> depth, discharge;
};

MarchedState marched_state(const solver::Canal& canal) {
  MarchedState state;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const auto& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i) state.depth.push_back(reach.depth(i));
    state.discharge.insert(state.discharge.end(), reach.discharge().begin(), reach.discharge().end());
  }
  return state;
}

double largest_change(const std::vector<double>& a, const std::vector<double>& b) {
  double largest = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) largest = std::max(largest, std::abs(a[k] - b[k]));
  return largest;
}

// Whether the canal moved less than a micrometre of depth and a millionth of its largest discharge
// between two states one chunk of marching apart — fifty times below the lab's 0.05 mm
// resolution, ten times the generalised minmod limiter's limit cycle (docs/numerics.md).
bool settled(const MarchedState& before, const MarchedState& now) {
  double q_scale = 0.0;
  for (double q : now.discharge) q_scale = std::max(q_scale, std::abs(q));
  return largest_change(before.depth, now.depth) <= kSettledDepth &&
         largest_change(before.discharge, now.discharge) <= kSettledDischarge * q_scale;
}

}  // namespace

// A warning through the caller's channel, else on stderr.
void warn(const SimulateOptions& options, const std::string& message) {
  if (options.warning) {
    options.warning(message);
  } else {
    std::fprintf(stderr, "canalsim: warning: %s\n", message.c_str());
  }
}

namespace {

// Sets the canal's clock and the controlled gate's state at `t`, the command held as it is then.
void set_time(BuiltCanal& b, double t) {
  b.canal.set_time(t);
  b.controlled->reset(t, b.controlled->command(t));
}

// Newton's steady state at `before_input`: the description for the recording's metadata when it
// converged (or stalled within the bounds), else its failure in `failure`.
std::string solve_by_newton(BuiltCanal& b, const Scenario& s, const ExperimentSpec& e, const SimulateOptions& options,
                            double before_input, std::string& failure) {
  const solver::SteadyStateOptions steady = initial_steady_state_options(s, e, options);
  // Solved early enough that its continuation marches end before the input starts: they march
  // with the boundaries running, and one that reached t > 0 settled the canal under the
  // experiment's first commands (the lab's op1 on 400 cells with minmod started at 0.61 L/s,
  // the steady flow of the PRBS's 20 mm, instead of the operating point's 0.48 L/s).
  set_time(b, before_input - solver::continuation_span(b.canal, steady));
  const auto summary = solver::solve_steady_state(b.canal, steady);
  set_time(b, before_input);
  if (!summary.status) {
    failure = summary.status.message();
    return "";
  }
  return "steady state (Newton, " + std::to_string(summary.iterations) + " iterations" +
         (summary.stalled ? "; " + summary.stall + ", every depth changing by less than " +
                                format_g(summary.max_depth_rate, 2) + " m/s" : "") + ")";
}

// The gates report the steady flow as their first sample's discharge (they have passed no step
// yet), and the reservoir's PID is preset so that the pump delivers the head gate's discharge.
void preset_structures(BuiltCanal& b) {
  if (b.head_gate) {
    const double q = b.canal.reach(0).discharge().front();
    b.head_gate->on_step_accepted(b.canal.time(), 0.0, q);
    if (b.reservoir) b.reservoir->reservoir().start_at_steady_state(q);
  }
  for (std::size_t i = 0; i < b.gate_links.size(); ++i) {
    // The gates between pools: the steady flow entering the next pool.
    b.gate_links[i]->on_step_accepted(b.canal.time(), 0.0, b.canal.reach(static_cast<int>(i) + 1).discharge().front());
  }
  if (b.tail_gate) {
    const auto& last = b.canal.reach(b.canal.reach_count() - 1);
    b.tail_gate->on_step_accepted(b.canal.time(), 0.0, last.discharge().back());
  }
}

// Marches `marching` seconds up to t = 0 in chunks for the progress line (the first
// `progress_weight` of the run's). `until_settled` (in place of a failed Newton) stops once two
// chunks in a row left the canal settled and the experiment's own settle_s has passed: on the
// lab's 400 cells with minmod that is after 120 of the 600 s. Returns the seconds marched.
double march_before_input(BuiltCanal& b, const ExperimentSpec& e, double marching, bool until_settled,
                          double progress_weight, const std::function<void(double)>& report, RunCostGuard& guard) {
  MarchedState before = marched_state(b.canal);
  int settled_chunks = 0;
  for (int k = 1; k <= kMarchingChunks; ++k) {
    march_to(b.canal, -marching + marching * k / kMarchingChunks, guard, "settling");
    report(progress_weight * k / kMarchingChunks);
    if (!until_settled) continue;
    MarchedState now = marched_state(b.canal);
    settled_chunks = settled(before, now) ? settled_chunks + 1 : 0;
    before = std::move(now);
    if (settled_chunks >= 2 && k < kMarchingChunks && marching * k / kMarchingChunks >= e.settle_s) {
      report(progress_weight);
      return marching * k / kMarchingChunks;
    }
  }
  return marching;
}

}  // namespace

InitialState settle(BuiltCanal& b, const Scenario& s, const ExperimentSpec& e, const SimulateOptions& options,
                    const std::function<void(double)>& report, RunCostGuard& guard) {
  InitialState result;
  const double before_input = -1e-9;  // strictly before the input starts
  set_time(b, before_input);
  std::string newton_failure;
  if (options.use_steady_state_solver) result.description = solve_by_newton(b, s, e, options, before_input, newton_failure);
  const bool solved = !result.description.empty();
  const double marching = solved ? e.settle_s : std::max({options.settle_time, e.settle_s, 0.0});
  if (marching > 0.0) set_time(b, -marching);
  preset_structures(b);
  double marched_s = marching;
  if (marching > 0.0) {
    result.progress_weight = 0.5;
    marched_s = march_before_input(b, e, marching, !solved, result.progress_weight, report, guard);
    const std::string marched = "time marching " + format_g(marched_s) + " s";
    result.description = solved ? result.description + ", then " + marched
                                : marched + (newton_failure.empty() ? "" : " (Newton: " + newton_failure + ")");
  }
  if (!newton_failure.empty()) warn_marched_start(b, s, e, options, newton_failure, marched_s);
  b.canal.set_time(0.0);
  b.canal.reset_balance();
  b.controlled->reset(0.0, b.controlled->opening(0.0));
  return result;
}

solver::SteadyStateOptions initial_steady_state_options(const Scenario& s, const ExperimentSpec& e,
                                                        const SimulateOptions& options) {
  solver::SteadyStateOptions steady;
  steady.depth_tolerance = std::max(1e-12, 1e-2 * s.numerics.steady_tolerance_m);
  // A Newton stalled by a limiter's kinks (solver/steady_state.hpp) is accepted when no depth
  // changes faster than the time marching that replaces a failed Newton accepts as settled
  // (settled(): kSettledDepth per chunk), and no discharge by more than kStalledDischarge per
  // chunk: the march would start further away and take 120-330 s of marching (the lab on 400
  // cells with minmod) to get there. Measured stalls of the lab on 200-800 cells: depths
  // 2e-10 to 7e-9 m/s (1/5000 to 1/5 of the bound), discharges 1e-6 to 9e-6 per chunk.
  const double fallback_chunk_s = std::max({options.settle_time, e.settle_s, 0.0}) / kMarchingChunks;
  if (fallback_chunk_s > 0.0) {
    steady.stalled_depth_rate = std::min(kSettledDepth / fallback_chunk_s, 1e-3);
    steady.stalled_discharge_rate = std::min(kStalledDischarge / fallback_chunk_s, 1e-3);
  }
  return steady;
}

}  // namespace canalsim::scenarios
