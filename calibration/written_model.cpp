#include "calibration/written_model.hpp"

#include <algorithm>
#include <memory>
#include <numeric>
#include <optional>
#include <string>

#include "calibration/fits.hpp"
#include "calibration/problem.hpp"
#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

scenarios::Scenario with_twice_the_cells(scenarios::Scenario s) {
  for (auto& pool : s.pools) pool.cells *= 2;
  return s;
}

std::string cells_text(const scenarios::Scenario& s) { return std::to_string(s.pools.front().cells) + " cells"; }

// A further doubling is tried while the last one cut the cost on the fitted recordings below this
// share of the cost before it: the grid, not the physics, still limits the model. Measured on the
// 1600-cell truth of docs/calibration.md: 0.0135 (estimates, 400 cells) -> 0.0070 (converged, 800)
// -> 0.0036 (converged, 1600), and op1* validated 4.9x on 800 cells, 7.9x on 1600.
constexpr double kStillGridLimited = 0.7;
constexpr int kMostDoublings = 2;  // up to four times the last grid's cells
// A finer grid is written only when it lowers that cost by a tenth: each doubling makes every
// replay of the written model four times the work, and a diagnosis replays each recording ~50
// times. On the second simulator's lab recordings of bench/README.md ("Diagnosis") 800 cells
// lowered it by 0.8 % against the estimates on 400, and a diagnosis against them takes 34 s
// where one against the 400 cells takes 10 s.
constexpr double kWorthFinerGrid = 0.9;
// Nor is it finer than eight times the scenario's own cells. On the second simulator's recordings
// of a 1200-cell truth (docs/calibration.md), with the regime border's floor fitted, 1600 lab
// cells fitted the recordings 22 % better than 800 (0.0112 against 0.0144) but the held-out levels
// 3 % (0.116 / 0.094 against 0.120 / 0.098 mm RMS), and a diagnosis against them took 32-41 s
// where one against 800 takes at most 16.4 s.
constexpr int kMostTimesTheScenariosCells = 8;

// The grid-converged estimates replayed on one finer grid (held by pointer: the problem refers to
// its scenario).
struct Candidate {
  std::unique_ptr<scenarios::Scenario> grid;
  std::unique_ptr<ReplayProblem> fit;
  std::vector<Channels> prediction;
  double cost = 0.0;
};

}  // namespace

void write_grid_converged(Calibration& c, const std::vector<Parameter>& parameters, const std::vector<Recording>& recordings,
                          const std::vector<Recording>& validation, const ReplayOptions& replay, int threads) {
  if (!c.ok || !c.grid.done || c.parameters.size() != parameters.size()) return;
  const bool moved = std::any_of(c.parameters.begin(), c.parameters.end(),
                                 [](const ParameterEstimate& p) { return p.converged != p.value; });
  if (!moved) return;
  std::vector<double> z(parameters.size());
  for (std::size_t j = 0; j < parameters.size(); ++j) z[j] = parameters[j].to_search(c.parameters[j].converged);
  std::optional<Candidate> best;
  std::string costs;  // "cost 0.007 on 800 cells, 0.0035 on 1600 cells"
  scenarios::Scenario grid = c.calibrated;  // holds the estimates; the candidates replace them by z
  double previous = c.cost_after;
  const int scenarios_cells = c.grids.empty() ? scenarios::total_cells(c.calibrated)
                                              : std::accumulate(c.grids.front().begin(), c.grids.front().end(), 0);
  for (int doubling = 1; doubling <= kMostDoublings; ++doubling) {
    if (2 * scenarios::total_cells(grid) > kMostTimesTheScenariosCells * scenarios_cells) break;
    grid = with_twice_the_cells(grid);
    Candidate next{std::make_unique<scenarios::Scenario>(grid), nullptr, {}, 0.0};
    next.fit = std::make_unique<ReplayProblem>(*next.grid, parameters, recordings, replay, threads);
    next.prediction = next.fit->predict(z);
    next.cost = cost_per_sample(next.fit->residuals(next.prediction));
    c.simulations += next.fit->simulations();
    costs += (costs.empty() ? "cost " : ", ") + format_g(next.cost, 3) + " on " + cells_text(grid);
    const bool still_limited = next.cost < kStillGridLimited * previous;
    previous = next.cost;
    if (next.cost < kWorthFinerGrid * (best ? best->cost : c.cost_after)) best = std::move(next);
    if (!still_limited) break;
  }
  const scenarios::Scenario finer = with_twice_the_cells(c.calibrated);
  const std::string compared = costs + " on the fitted recordings, against " + format_g(c.cost_after, 3) +
                               " with the estimates on " + cells_text(c.calibrated) + " and " +
                               format_g(c.grid.refined_cost, 3) + " with them on " + cells_text(finer);
  if (!best) {
    c.written_note = "the estimates on " + cells_text(c.calibrated) + " (the grid-converged ones: " + compared +
                     "; a finer grid is written when it lowers the cost by a tenth)";
    return;
  }
  const int cells_before = c.calibrated.pools.front().cells;
  c.calibrated = best->fit->scenario_at(z);
  c.written_grid_converged = true;
  c.written_cells_factor = c.calibrated.pools.front().cells / cells_before;
  c.written_note = "the grid-converged estimates on " + cells_text(c.calibrated) + " (" + compared +
                   "); the figures after calibration are this model's";
  restate_fits(*best->fit, best->prediction, false, FitSide::after, c);
  if (!validation.empty()) {
    ReplayProblem check(c.calibrated, parameters, validation, replay, threads, &best->fit->weights());
    restate_fits(check, check.predict(z), true, FitSide::after, c);
    c.simulations += check.simulations();
  }
}

}  // namespace canalsim::calibration
