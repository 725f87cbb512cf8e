#include "calibration/written_model.hpp"

#include <algorithm>
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

}  // namespace

void write_grid_converged(Calibration& c, const std::vector<Parameter>& parameters, const std::vector<Recording>& recordings,
                          const std::vector<Recording>& validation, const ReplayOptions& replay, int threads) {
  if (!c.ok || !c.grid.done || c.parameters.size() != parameters.size()) return;
  const bool moved = std::any_of(c.parameters.begin(), c.parameters.end(),
                                 [](const ParameterEstimate& p) { return p.converged != p.value; });
  if (!moved) return;
  const scenarios::Scenario finer = with_twice_the_cells(c.calibrated);  // holds the estimates
  ReplayProblem fit(finer, parameters, recordings, replay, threads);
  std::vector<double> z(parameters.size());
  for (std::size_t j = 0; j < parameters.size(); ++j) z[j] = parameters[j].to_search(c.parameters[j].converged);
  const std::vector<Channels> prediction = fit.predict(z);
  const double cost = cost_per_sample(fit.residuals(prediction));
  c.simulations += fit.simulations();
  const std::string compared = "cost " + format_g(cost, 3) + " on the fitted recordings, against " +
                               format_g(c.cost_after, 3) + " with the estimates on " + cells_text(c.calibrated) +
                               " and " + format_g(c.grid.refined_cost, 3) + " with them on " + cells_text(finer);
  if (!(cost < c.cost_after)) {
    c.written_note = "the estimates on " + cells_text(c.calibrated) + " (the grid-converged ones on " + cells_text(finer) +
                     ": " + compared + ")";
    return;
  }
  c.calibrated = fit.scenario_at(z);
  c.written_grid_converged = true;
  c.written_note = "the grid-converged estimates on " + cells_text(finer) + " (" + compared +
                   "); the figures after calibration are this model's";
  restate_fits(fit, prediction, false, FitSide::after, c);
  if (!validation.empty()) {
    ReplayProblem check(finer, parameters, validation, replay, threads, &fit.weights());
    restate_fits(check, check.predict(z), true, FitSide::after, c);
    c.simulations += check.simulations();
  }
}

}  // namespace canalsim::calibration
