#include "calibration/discretisation.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <string>
#include <utility>

#include "calibration/statistics.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::calibration {
namespace {

using scenarios::Scenario;

constexpr const char* kTwiceTheCells = "twice the cells";

struct Alternative {
  const char* name;
  double weight;
  std::function<void(Scenario&)> edit;
};

const std::vector<Alternative>& alternatives() {
  static const std::vector<Alternative> list = {
      {kTwiceTheCells, richardson_factor(kGridOrder), [](Scenario& s) { s = scenarios::with_cells_multiplied(std::move(s), 2); }},
      {"the other limiter", 1.0, [](Scenario& s) { s.numerics.van_leer_limiter = !s.numerics.van_leer_limiter; }},
      {"half the Courant number", 1.0, [](Scenario& s) { s.numerics.cfl *= 0.5; }},
  };
  return list;
}

std::vector<double> clamp_to_bounds(const std::vector<Parameter>& parameters, std::vector<double> z) {
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    const double lo = parameters[j].to_search(parameters[j].low), hi = parameters[j].to_search(parameters[j].high);
    z[j] = std::clamp(z[j], std::min(lo, hi), std::max(lo, hi));
  }
  return z;
}

// θ(to) − θ(from) per parameter, in parameter units.
std::vector<double> parameter_move(const std::vector<Parameter>& parameters, const std::vector<double>& from,
                         const std::vector<double>& to) {
  std::vector<double> out;
  for (std::size_t j = 0; j < parameters.size(); ++j) out.push_back(parameters[j].from_search(to[j]) - parameters[j].from_search(from[j]));
  return out;
}

// Gauss–Newton with the Jacobian of the optimum held fixed: z_{k+1} = z_k + argmin |r_alt(z_k) + J δ|.
DiscretisationShift re_estimate(ReplayProblem& problem, const std::vector<double>& z, const std::vector<double>& J,
                                const Alternative& a, int iterations, const std::vector<Channels>* first_prediction) {
  const auto& parameters = problem.parameters();
  DiscretisationShift out;
  out.name = a.name;
  out.weight = a.weight;
  std::vector<double> zk = z;
  for (int k = 0; k < iterations; ++k) {
    Scenario s = problem.scenario_at(zk);
    a.edit(s);
    const std::vector<Channels> prediction = k == 0 && first_prediction ? *first_prediction : problem.predict(s);
    const std::vector<double> r = problem.residuals(prediction);
    if (k == 0) {
      out.at_optimum = prediction;
      out.cost = cost_per_sample(r);
    }
    const std::vector<double> step = optimum_shift(J, r, parameters.size());
    for (std::size_t j = 0; j < zk.size(); ++j) zk[j] += step[j];
    zk = clamp_to_bounds(parameters, zk);
    if (k == 0) out.linear_response = parameter_move(parameters, z, zk);
  }
  out.shift = parameter_move(parameters, z, zk);
  return out;
}

}  // namespace

std::vector<DiscretisationShift> discretisation_shifts(ReplayProblem& problem, const std::vector<double>& z,
                                                       const std::vector<double>& jacobian, int iterations,
                                                       const std::vector<Channels>* twice_the_cells_at_z) {
  std::vector<DiscretisationShift> out;
  for (const Alternative& a : alternatives()) {
    const bool cells = std::string(a.name) == kTwiceTheCells;
    out.push_back(re_estimate(problem, z, jacobian, a, iterations, cells ? twice_the_cells_at_z : nullptr));
  }
  return out;
}

Scenario twice_the_cells(const ReplayProblem& problem, const std::vector<double>& z) {
  return scenarios::with_cells_multiplied(problem.scenario_at(z), 2);
}

std::vector<double> numerical_uncertainty(const std::vector<DiscretisationShift>& shifts, std::size_t parameters) {
  std::vector<double> u(parameters, 0.0);
  for (std::size_t j = 0; j < parameters; ++j) {
    double sum = 0.0;
    for (const auto& s : shifts) sum += (s.weight * s.shift[j]) * (s.weight * s.shift[j]);
    u[j] = std::sqrt(sum);
  }
  return u;
}

std::vector<double> grid_converged(const std::vector<Parameter>& parameters, const std::vector<double>& values,
                                   const std::vector<DiscretisationShift>& shifts) {
  const auto cells = std::find_if(shifts.begin(), shifts.end(), [](const auto& s) { return s.name == kTwiceTheCells; });
  if (cells == shifts.end()) return values;
  std::vector<double> out = values;
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    const double lo = std::min(parameters[j].low, parameters[j].high), hi = std::max(parameters[j].low, parameters[j].high);
    out[j] = std::clamp(values[j] + richardson_factor(kGridOrder) * cells->linear_response[j], lo, hi);
  }
  return out;
}

}  // namespace canalsim::calibration
