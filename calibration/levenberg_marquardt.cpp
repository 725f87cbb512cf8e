#include "calibration/levenberg_marquardt.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <string>

#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

// The least-squares problem as Ceres sees it: one residual block of all residuals on one
// parameter block, the search coordinates of the parameters not held at a bound (`free`; the held
// ones keep their values in `full`). Jacobians by ReplayProblem's parallel forward differences. A
// simulation that fails makes the point unusable (Ceres then shrinks its step).
class ReplayCost : public ceres::CostFunction {
 public:
  ReplayCost(ReplayProblem& problem, std::vector<double> full, std::vector<std::size_t> free)
      : problem_(problem), full_(std::move(full)), free_(std::move(free)) {
    set_num_residuals(static_cast<int>(problem.residual_count()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(free_.size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    std::vector<double> z = full_;
    for (std::size_t k = 0; k < free_.size(); ++k) z[free_[k]] = parameters[0][k];
    try {
      const std::vector<double> r = problem_.residuals(problem_.predict(z));
      // Ceres is given finite numbers or a failed evaluation (it then shortens the step).
      if (!std::all_of(r.begin(), r.end(), [](double v) { return std::isfinite(v); })) return false;
      std::copy(r.begin(), r.end(), residuals);
      if (jacobians && jacobians[0]) {
        const std::vector<double> J = problem_.jacobian(z, r);
        if (!std::all_of(J.begin(), J.end(), [](double v) { return std::isfinite(v); })) return false;
        const std::size_t p = z.size(), f = free_.size();
        for (std::size_t row = 0; row < r.size(); ++row) {
          for (std::size_t k = 0; k < f; ++k) jacobians[0][row * f + k] = J[row * p + free_[k]];
        }
      }
    } catch (const std::exception&) {
      return false;
    }
    return true;
  }

 private:
  ReplayProblem& problem_;
  std::vector<double> full_;
  std::vector<std::size_t> free_;
};

class IterationProgress : public ceres::IterationCallback {
 public:
  IterationProgress(const ProgressCallback& progress, int run, int runs, int max_iterations)
      : progress_(progress), run_(run), runs_(runs), max_(max_iterations) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (progress_) {
      const double within = std::min(1.0, static_cast<double>(s.iteration + 1) / max_);
      progress_({0.1 + 0.8 * (run_ + within) / runs_, "start " + std::to_string(run_ + 1) + "/" + std::to_string(runs_) +
                                                          ", iteration " + std::to_string(s.iteration) + ", cost " +
                                                          format_g(s.cost, 4)});
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const ProgressCallback& progress_;
  int run_, runs_, max_;
};

// A run stops when a step fails although the quadratic model promised less than this fraction of
// the cost: the model is then wrong at the scale of the improvement still on offer (the
// forward-difference Jacobian's error and the simulation's own roughness exceed it), and Ceres
// would halve its trust region, one evaluation of every recording each, until the step changed —
// the radius is 1e4–1e7 there, far above the step, and the same step failed up to six times.
// Measured on four lab recordings of an 800-cell truth, calibrated on 100, 200 and 400 cells
// (bench/README.md, "Grid refinement"): the last failed steps promised 4.5e-4 to 7e-4 of the cost;
// stopping there took 688 simulations instead of 900 for a final cost 0.06 % higher. A thousandth
// of the cost is 1.6–4.5 times what one standard deviation of the estimates changes it by at
// those optima (inflation / samples = 2.2e-4 to 6.1e-4).
constexpr double kModelResolution = 1e-3;

class StopAtTheModelsResolution : public ceres::IterationCallback {
 public:
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (s.step_is_successful || s.relative_decrease == 0.0) return ceres::SOLVER_CONTINUE;
    const double promised = s.cost_change / s.relative_decrease;  // the model's decrease
    return promised < kModelResolution * s.cost ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
};


// With secant Jacobians (ReplayProblem::use_secant_updates), a step that failed asks for the
// next Jacobian by differences: the secant one's model of the cost was wrong at that scale.
class RefreshTheJacobianAfterAFailedStep : public ceres::IterationCallback {
 public:
  explicit RefreshTheJacobianAfterAFailedStep(ReplayProblem& problem) : problem_(problem) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (!s.step_is_successful) problem_.refresh_jacobian();
    return ceres::SOLVER_CONTINUE;
  }

 private:
  ReplayProblem& problem_;
};

// Stops a run when a step it accepted put a free parameter on its bound: Ceres projects its
// unconstrained step onto the bounds, so every later step still spends part of itself pushing that
// parameter outwards and the projected steps creep (on the lab's 400 cells with
// downstream_zero_head_mm resting at its published 0, seven differenced iterations took the cost
// from 114.1 to 113.7). The run then continues with it held there (active set, Nocedal & Wright
// 2006, §16.5), and releases it when the cost's gradient points inside.
class StopOnReachingABound : public ceres::IterationCallback {
 public:
  // `watched`: per free parameter, whether reaching a bound stops the run.
  StopOnReachingABound(const std::vector<double>& x, std::vector<double> low, std::vector<double> high,
                       std::vector<bool> watched)
      : x_(x), low_(std::move(low)), high_(std::move(high)), watched_(std::move(watched)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (s.iteration == 0 || !s.step_is_successful) return ceres::SOLVER_CONTINUE;
    for (std::size_t k = 0; k < x_.size(); ++k) {
      if (watched_[k] && (x_[k] <= low_[k] || x_[k] >= high_[k])) reached_.push_back(k);
    }
    return reached_.empty() ? ceres::SOLVER_CONTINUE : ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }
  const std::vector<std::size_t>& reached() const { return reached_; }

 private:
  const std::vector<double>& x_;  // Ceres' parameter block, current at every callback
  std::vector<double> low_, high_;
  std::vector<bool> watched_;
  std::vector<std::size_t> reached_;
};

struct Leg {
  std::vector<std::size_t> reached;  // free parameters (indices into z) a step put on a bound
  int iterations = 0;
  std::string report;
  bool converged = false;
  double cost = std::numeric_limits<double>::infinity();
};

ceres::Solver::Options solver_options(int max_iterations, double function_tolerance) {
  ceres::Solver::Options so;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 1;  // the parallelism is in the simulations
  so.logging_type = ceres::SILENT;
  so.function_tolerance = function_tolerance;
  so.parameter_tolerance = 1e-5;
  so.gradient_tolerance = 1e-10;
  // No projected line search on the bounds: Ceres would evaluate the Jacobian (a simulation per
  // hydraulic parameter and recording) at every line-search point as well, which more than
  // doubled the simulations; the bounds still hold, the step being projected onto them.
  so.max_num_line_search_step_size_iterations = 0;
  so.update_state_every_iteration = true;  // StopOnReachingABound reads the parameters
  return so;
}

// One Ceres solve over the parameters not `held`, from z (updated in place); it stops when a
// parameter not `released` before reaches a bound.
Leg solve_free(ReplayProblem& problem, std::vector<double>& z, const std::vector<bool>& held,
               const std::vector<bool>& released, int max_iterations, const ProgressCallback& progress_to, int run,
               int runs, double function_tolerance, bool secant) {
  const auto& params = problem.parameters();
  std::vector<std::size_t> free;
  std::vector<double> x, low, high;
  std::vector<bool> watched;
  for (std::size_t j = 0; j < params.size(); ++j) {
    if (held[j]) continue;
    free.push_back(j);
    watched.push_back(!released[j]);
    x.push_back(z[j]);
    low.push_back(params[j].to_search(params[j].low));
    high.push_back(params[j].to_search(params[j].high));
  }
  ReplayCost cost(problem, z, free);
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem lsq(po);
  lsq.AddResidualBlock(&cost, nullptr, x.data());
  for (std::size_t k = 0; k < free.size(); ++k) {
    lsq.SetParameterLowerBound(x.data(), static_cast<int>(k), low[k]);
    lsq.SetParameterUpperBound(x.data(), static_cast<int>(k), high[k]);
  }
  ceres::Solver::Options so = solver_options(max_iterations, function_tolerance);
  IterationProgress progress(progress_to, run, runs, max_iterations);
  so.callbacks.push_back(&progress);
  StopAtTheModelsResolution resolution;
  so.callbacks.push_back(&resolution);
  StopOnReachingABound bound(x, low, high, watched);
  so.callbacks.push_back(&bound);
  RefreshTheJacobianAfterAFailedStep refresh(problem);
  if (secant) so.callbacks.push_back(&refresh);
  problem.use_secant_updates(secant);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &lsq, &summary);
  problem.use_secant_updates(false);
  for (std::size_t k = 0; k < free.size(); ++k) z[free[k]] = x[k];
  Leg leg;
  for (std::size_t k : bound.reached()) leg.reached.push_back(free[k]);
  leg.iterations = static_cast<int>(summary.iterations.size());
  leg.report = summary.BriefReport();
  leg.converged = summary.termination_type == ceres::CONVERGENCE || summary.termination_type == ceres::USER_SUCCESS;
  if (summary.IsSolutionUsable()) leg.cost = 2.0 * summary.final_cost / static_cast<double>(problem.residual_count());
  return leg;
}

// The held parameters whose cost gradient J^T r at z points inside their bounds: moving them off
// the bound would lower the cost (the Karush–Kuhn–Tucker sign test). The Jacobian is the one the
// run took at z (ReplayProblem caches it), so the test costs no simulation.
std::vector<std::size_t> held_that_would_leave(ReplayProblem& problem, const std::vector<double>& z,
                                               const std::vector<bool>& held) {
  const auto& params = problem.parameters();
  const std::size_t p = params.size();
  const std::vector<double> r = problem.residuals(problem.predict(z));
  const std::vector<double> J = problem.jacobian(z, r);
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < p; ++j) {
    if (!held[j]) continue;
    double gradient = 0.0;
    for (std::size_t row = 0; row < r.size(); ++row) gradient += J[row * p + j] * r[row];
    const bool at_low = z[j] <= params[j].to_search(params[j].low);
    if (at_low ? gradient < 0.0 : gradient > 0.0) out.push_back(j);
  }
  return out;
}

}  // namespace

Run levenberg_marquardt(ReplayProblem& problem, std::vector<double> z, int max_iterations, const ProgressCallback& progress_to,
                        int run, int runs, double function_tolerance, bool secant) {
  const std::size_t p = problem.parameters().size();
  std::vector<bool> held(p, false), released(p, false);
  Run out;
  out.z = z;
  // Each leg either holds a parameter more, or releases one never released before: at most 2p + 1.
  for (std::size_t leg_count = 0; leg_count <= 2 * p && out.iterations < max_iterations; ++leg_count) {
    if (std::find(held.begin(), held.end(), false) != held.end()) {
      const Leg leg = solve_free(problem, z, held, released, max_iterations - out.iterations, progress_to, run, runs,
                                 function_tolerance, secant);
      out.iterations += leg.iterations;
      out.report = leg.report;
      if (!std::isfinite(leg.cost)) break;
      out.z = z;
      out.cost = leg.cost;
      out.converged = leg.converged;
      if (!leg.reached.empty()) {
        for (std::size_t j : leg.reached) held[j] = true;
        out.converged = false;  // continued with the parameter held
        continue;
      }
      if (!leg.converged) break;
    }
    if (std::find(held.begin(), held.end(), true) == held.end()) break;
    std::vector<std::size_t> leaving;
    try {
      leaving = held_that_would_leave(problem, z, held);
    } catch (const std::exception&) {
      break;
    }
    out.converged = leaving.empty();  // every held parameter pushes outwards: a bounded optimum
    if (leaving.empty()) break;
    for (std::size_t j : leaving) {
      held[j] = false;
      released[j] = true;  // from here on Ceres' projection keeps it within its bounds
    }
  }
  return out;
}

}  // namespace canalsim::calibration
