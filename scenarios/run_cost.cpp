#include "scenarios/run_cost.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "core/format.hpp"

namespace canalsim::scenarios {
namespace {

constexpr double kGravity = 9.81;
// Per recorded sample: every column three times over (sensor series, recording, copies while
// writing) plus its text (~16 characters a field).
constexpr double kBytesPerField = 3 * 8 + 16;
// Per cell: the solver's ~30 state and work arrays and the steady-state Jacobian's nonzeros.
constexpr double kBytesPerCell = 1000.0;
// The second-order step's measured speed, one core (bench/README.md).
constexpr double kCellUpdatesPerSecond = 1.0e8;

double busy_threads(int threads, std::size_t recordings) {
  return std::max(1.0, std::min(static_cast<double>(threads), static_cast<double>(recordings)));
}

}  // namespace

double replays_ceiling(int threads, std::size_t recordings) { return kMaxCellUpdates * busy_threads(threads, recordings); }

std::string replays_ceiling_text(int threads, std::size_t recordings) {
  const double busy = busy_threads(threads, recordings);
  return format_g(replays_ceiling(threads, recordings)) +
         (busy > 1.0 ? " (" + format_g(kMaxCellUpdates) + " on each of " + format_g(busy) + " threads)" : std::string());
}

RunCost estimate_replay_cost(const Scenario& s, const Recording& recording) {
  ExperimentSpec replay;
  replay.name = recording.source;
  const auto& t = recording.column(columns::time);
  replay.duration_s = t.back() - t.front();
  return estimate_run_cost(s, replay, recording.sample_period());
}

RunCost estimate_run_cost(const Scenario& s, const ExperimentSpec& e, double h) {
  RunCost cost;
  cost.samples = std::floor(e.duration_s / h + 1e-9) + 1.0;
  double cells = 0.0, shortest_step = INFINITY;
  for (const PoolSpec& pool : s.pools) {
    cells += pool.cells;
    const double dx = pool.length_m / pool.cells;
    const double celerity = std::sqrt(kGravity * pool.wall_height_m);
    shortest_step = std::min(shortest_step, s.numerics.cfl * dx / celerity);
  }
  cost.time_steps = (e.duration_s + e.settle_s) / shortest_step;
  // Every run ends a step at each jump of the command: a PRBS clocked far faster than the waves
  // adds a step a bit.
  if (e.input.kind == InputKind::prbs) cost.time_steps += e.duration_s / e.input.prbs_clock_s;
  cost.cell_updates = cells * cost.time_steps;
  const double columns = 9.0 + (s.pools.size() > 1 ? static_cast<double>(s.pools.size()) : 0.0);
  cost.memory_bytes = cost.samples * columns * kBytesPerField + cells * kBytesPerCell;
  return cost;
}

void check_run_cost(const Scenario& s, const ExperimentSpec& e, double h, bool allow_long) {
  const std::string where = s.source + ": experiment '" + e.name + "': ";
  const RunCost cost = estimate_run_cost(s, e, h);
  if (!(cost.samples >= 2.0)) {
    throw InputError(where + "duration_s = " + format_g(e.duration_s) + " s with sensors.period_s = " +
                     format_g(h) + " s gives one sample: expected duration_s >= period_s (at least two samples)");
  }
  if (!(cost.samples <= kMaxSamples)) {
    throw InputError(where + "duration_s = " + format_g(e.duration_s) + " s with sensors.period_s = " +
                     format_g(h) + " s gives " + format_g(cost.samples, 3) + " samples: expected at most " +
                     format_g(kMaxSamples) + " (a longer period_s or a shorter duration_s)");
  }
  if (allow_long) return;
  if (cost.memory_bytes > kMaxMemoryBytes) {
    throw InputError(where + format_g(cost.samples, 3) + " samples need about " + format_g(cost.memory_bytes / 1e9, 3) +
                     " GB: expected at most " + format_g(kMaxMemoryBytes / 1e9) +
                     " GB (raise sensors.period_s, shorten duration_s, or pass --allow-long)");
  }
  if (cost.cell_updates > kMaxCellUpdates) {
    const double minutes = cost.cell_updates / kCellUpdatesPerSecond / 60.0;
    throw InputError(where + "about " + format_g(cost.time_steps, 3) + " time steps × the cells = " +
                     format_g(cost.cell_updates, 3) + " cell updates (~" + format_g(minutes, 2) +
                     " minutes of computing): expected at most " +
                     format_g(kMaxCellUpdates) + " (fewer cells, a larger cfl, a shorter duration_s or settle_s; "
                     "or pass --allow-long)");
  }
}

RunCostGuard::RunCostGuard(const Scenario& s, const ExperimentSpec& e, bool allow_long)
    : where_(s.source + ": experiment '" + e.name + "': "), end_(e.duration_s), allow_long_(allow_long) {
  cells_ = total_cells(s);
}

void RunCostGuard::check(long steps, double time, double last_step) {
  if (allow_long_) return;
  if (!started_) {
    started_ = true;
    first_steps_ = window_steps_ = steps;
    window_time_ = time;
    return;
  }
  // The pace of the last window of steps, not the average since the start: a pool that runs dry
  // after a minute of normal steps takes 1e-9 s steps from then on.
  constexpr long kWindow = 20000;
  if (steps - window_steps_ < kWindow) return;
  const double pace = (time - window_time_) / static_cast<double>(steps - window_steps_);  // s per step
  window_steps_ = steps;
  window_time_ = time;
  const double remaining = pace > 0.0 ? std::max(end_ - time, 0.0) / pace : INFINITY;
  const double projected = cells_ * (static_cast<double>(steps - first_steps_) + remaining);
  if (projected <= kMaxCellUpdates) return;
  throw InputError(where_ + "at t = " + format_g(time) + " s the time step is " + format_g(last_step, 3) +
                   " s (" + format_g(pace, 3) + " s on average over the last " + std::to_string(kWindow) +
                   " steps): the whole run would take about " + format_g(projected, 3) +
                   " cell updates, expected at most " + format_g(kMaxCellUpdates) +
                   " (a flow far faster than the canal's waves, or a pool running dry: check the inflow, "
                   "offtakes, widths and openings; or pass --allow-long)");
}

}  // namespace canalsim::scenarios
