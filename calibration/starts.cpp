#include "calibration/starts.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

#include "core/format.hpp"

namespace canalsim::calibration {

std::vector<Run> screened_starts(ReplayProblem& problem, int count) {
  const auto& params = problem.parameters();
  std::vector<Run> out;
  for (int k = 1; k <= count; ++k) {
    Run r;
    for (std::size_t j = 0; j < params.size(); ++j) {
      const double alpha = std::sqrt(static_cast<double>(2 + 3 * j)) - std::floor(std::sqrt(static_cast<double>(2 + 3 * j)));
      const double f = std::fmod(0.5 + k * alpha, 1.0);
      const double lo = params[j].to_search(params[j].low), hi = params[j].to_search(params[j].high);
      r.z.push_back(lo + (hi - lo) * (0.25 + 0.5 * f));
    }
    try {
      r.cost = cost_per_sample(problem.residuals(problem.predict(r.z)));
      out.push_back(std::move(r));
    } catch (const std::exception&) {
    }
  }
  std::sort(out.begin(), out.end(), [](const Run& a, const Run& b) { return a.cost < b.cost; });
  return out;
}

// Parameter by parameter: those before j as moved, those after as they start.
std::vector<double> start_at_the_scans(ReplayProblem& fit, std::vector<double> z, double cost_at_z, const ProgressCallback& progress,
                                       std::string& note) {
  const std::vector<Parameter>& parameters = fit.parameters();
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    const Parameter& p = parameters[j];
    if (p.scan.empty()) continue;
    if (progress) progress({0.0, "scanning " + p.name + " for a start"});
    double best_z = z[j];
    std::string tried = format_g(p.from_search(z[j]), 3);
    for (const double value : p.scan) {
      if (value < p.low || value > p.high) continue;
      std::vector<double> trial = z;
      trial[j] = p.to_search(value);
      const double cost = cost_per_sample(fit.residuals(fit.predict(trial)));
      tried += ", " + format_g(value, 3);
      if (cost < cost_at_z) {
        cost_at_z = cost;
        best_z = trial[j];
      }
    }
    z[j] = best_z;
    note += (note.empty() ? "" : "; ") + p.name + " started at " + format_g(p.from_search(best_z), 3) + " " + p.unit +
            ", the lowest cost of " + tried;
  }
  return z;
}

}  // namespace canalsim::calibration
