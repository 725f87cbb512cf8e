#include "calibration/levenberg_marquardt.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <exception>
#include <string>

#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

// The least-squares problem as Ceres sees it: one residual block of all residuals on one
// parameter block (the search coordinates). Jacobians by ReplayProblem's parallel forward
// differences. A simulation that fails makes the point unusable (Ceres then shrinks its step).
class ReplayCost : public ceres::CostFunction {
 public:
  explicit ReplayCost(ReplayProblem& problem) : problem_(problem) {
    set_num_residuals(static_cast<int>(problem.residual_count()));
    mutable_parameter_block_sizes()->push_back(static_cast<int>(problem.parameters().size()));
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const std::size_t p = problem_.parameters().size();
    const std::vector<double> z(parameters[0], parameters[0] + p);
    try {
      const std::vector<double> r = problem_.residuals(problem_.predict(z));
      std::copy(r.begin(), r.end(), residuals);
      if (jacobians && jacobians[0]) {
        const std::vector<double> J = problem_.jacobian(z, r);
        std::copy(J.begin(), J.end(), jacobians[0]);
      }
    } catch (const std::exception&) {
      return false;
    }
    return true;
  }

 private:
  ReplayProblem& problem_;
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

}  // namespace

Run levenberg_marquardt(ReplayProblem& problem, std::vector<double> z, int max_iterations, const ProgressCallback& progress_to,
                        int run, int runs, double function_tolerance, bool secant) {
  ReplayCost cost(problem);
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem lsq(po);
  lsq.AddResidualBlock(&cost, nullptr, z.data());
  const auto& params = problem.parameters();
  for (std::size_t j = 0; j < params.size(); ++j) {
    lsq.SetParameterLowerBound(z.data(), static_cast<int>(j), params[j].to_search(params[j].low));
    lsq.SetParameterUpperBound(z.data(), static_cast<int>(j), params[j].to_search(params[j].high));
  }
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
  IterationProgress progress(progress_to, run, runs, max_iterations);
  so.callbacks.push_back(&progress);
  StopAtTheModelsResolution resolution;
  so.callbacks.push_back(&resolution);
  RefreshTheJacobianAfterAFailedStep refresh(problem);
  if (secant) so.callbacks.push_back(&refresh);
  problem.use_secant_updates(secant);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &lsq, &summary);
  problem.use_secant_updates(false);
  Run out;
  out.z = z;
  out.iterations = static_cast<int>(summary.iterations.size());
  out.report = summary.BriefReport();
  out.converged = summary.termination_type == ceres::CONVERGENCE || summary.termination_type == ceres::USER_SUCCESS;
  if (summary.IsSolutionUsable()) out.cost = 2.0 * summary.final_cost / static_cast<double>(problem.residual_count());
  return out;
}

}  // namespace canalsim::calibration
