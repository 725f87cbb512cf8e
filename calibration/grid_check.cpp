#include "calibration/grid_check.hpp"

#include <cmath>
#include <string>

#include "calibration/discretisation.hpp"
#include "calibration/observe.hpp"
#include "core/format.hpp"

namespace canalsim::calibration {

const TwiceTheCells::Replayed& TwiceTheCells::replay(const std::vector<double>& z) {
  if (!last_ || last_->z != z) {
    const scenarios::Scenario finer = twice_the_cells(problem_, z);
    Replayed r{z, problem_.simulate_all(finer), {}};
    r.observed = problem_.observe_all(r.truth, finer);
    last_ = std::move(r);
  }
  return *last_;
}

GridCheck grid_check(const ReplayProblem& problem, const std::vector<Channels>& fine,
                     const std::vector<Channels>& at_optimum, double cost) {
  GridCheck g;
  g.done = true;
  g.cost = cost;
  g.refined_cost = cost_per_sample(problem.residuals(fine));
  double change = 0.0, residual = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < fine.size(); ++i) {
    for (const auto& [channel, y] : problem.replays()[i].data) {
      if (!is_level(channel) || !fine[i].count(channel)) continue;
      const auto& a = at_optimum[i].at(channel);
      const auto& f = fine[i].at(channel);
      for (std::size_t k = 0; k < y.size(); ++k) {
        change += (f[k] - a[k]) * (f[k] - a[k]);
        residual += (y[k] - a[k]) * (y[k] - a[k]);
        ++n;
      }
    }
  }
  g.rms_change = n ? std::sqrt(change / static_cast<double>(n)) : 0.0;
  g.residual_rms = n ? std::sqrt(residual / static_cast<double>(n)) : 0.0;
  const double relative = g.cost > 0.0 ? (g.refined_cost - g.cost) / g.cost : 0.0;
  if (g.rms_change > 0.5 * g.residual_rms) {
    g.verdict = "the grid limits the fit: twice the cells move the levels by " + format_g(g.rms_change, 3) +
                " mm RMS, comparable with the residual (" + format_g(g.residual_rms, 3) + " mm)";
  } else {
    g.verdict = "the grid does not limit the fit: twice the cells move the levels by " + format_g(g.rms_change, 3) +
                " mm RMS against a residual of " + format_g(g.residual_rms, 3) + " mm (cost " +
                (relative >= 0 ? "+" : "") + format_fixed(100.0 * relative, 1) + " %)";
  }
  return g;
}

}  // namespace canalsim::calibration
