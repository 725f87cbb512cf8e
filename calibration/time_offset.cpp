#include "calibration/time_offset.hpp"

#include <cmath>
#include <numeric>

#include "calibration/parameters.hpp"
#include "calibration/problem.hpp"

namespace canalsim::calibration {

TimeOffsetScan scan_time_offset(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings,
                                const ReplayOptions& replay, int threads, double range_s, double step_s) {
  ReplayProblem problem(scenario, select_parameters(scenario, {"sensor_delay_s"}), recordings, replay, threads);
  const double own = problem.start().front();
  // The delay only re-observes the simulations of the first point (ReplayProblem::predict).
  const auto cost_at = [&problem](double delay) {
    const std::vector<double> r = problem.residuals(problem.predict({delay}));
    return std::inner_product(r.begin(), r.end(), r.begin(), 0.0) / static_cast<double>(r.size());
  };
  TimeOffsetScan scan;
  scan.cost_at_zero = cost_at(own);
  scan.delay_s = own;
  scan.cost_at_best = scan.cost_at_zero;
  const int steps = static_cast<int>(std::round(range_s / step_s));
  for (int k = -steps; k <= steps; ++k) {
    const double delay = own + k * step_s;
    if (const double cost = cost_at(delay); cost < scan.cost_at_best) {
      scan.cost_at_best = cost;
      scan.delay_s = delay;
    }
  }
  // Golden-section search within a step of the best point of the scan.
  constexpr double kGolden = 0.6180339887498949;
  double a = scan.delay_s - step_s, b = scan.delay_s + step_s;
  while (b - a > 1e-3) {
    const double c = b - kGolden * (b - a), d = a + kGolden * (b - a);
    if (cost_at(c) < cost_at(d)) {
      b = d;
    } else {
      a = c;
    }
  }
  if (const double cost = cost_at(0.5 * (a + b)); cost < scan.cost_at_best) {
    scan.cost_at_best = cost;
    scan.delay_s = 0.5 * (a + b);
  }
  return scan;
}

}  // namespace canalsim::calibration
