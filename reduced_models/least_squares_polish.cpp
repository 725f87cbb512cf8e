// The least-squares polish of a fit (identification.hpp, Criterion::least_squares) by bounded
// Levenberg–Marquardt (Ceres Solver, as the calibration's).
//
// The residuals, one per sample of every recording j, weighted as the criterion h Σ e² weighs them:
//
//     e_jk = sqrt(h_j) (R(μ_jk) − y_jk),   μ_jk = y0_j + c_j + K g_jk(θ),
//
// with g the unit-gain response (Problem::unit_responses), θ the model's other free parameters
// (T, λ, L, …), c_j the output offset of recording j, and R the sensor's mean reading μ + b(μ)
// (sensor_reading.hpp), or μ itself. The Jacobian is exact in K and the offsets —
// ∂e/∂K = sqrt(h) R'(μ) g, ∂e/∂c_j = sqrt(h) R'(μ) — and by forward differences of the response
// in θ, ∂e/∂θ_i = sqrt(h) R'(μ) K ∂g/∂θ_i: one simulation per parameter and iteration, none for L
// (a linear model's response is re-delayed from its cached undelayed form). Near the optimum
// Gauss–Newton converges in a few iterations where a derivative-free search spent hundreds of
// simulations resolving a cost change of σ² in n σ² (a relative 1/n).
#include <algorithm>
#include <cmath>
#include <utility>

#include <ceres/ceres.h>

#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced::detail {
namespace {

// Ceres' parameter blocks: θ (the free parameters other than K, in free_names() order), K, and
// the offsets c_j.
class ReadingResiduals final : public ceres::CostFunction {
 public:
  // `bounds`: θ's, the polish's L bracket included (the differences are one-sided at the upper).
  ReadingResiduals(Problem& problem, const std::vector<const ExperimentData*>& data, const Model& base,
                   std::vector<std::string> names, std::vector<std::pair<double, double>> bounds,
                   const ReadingBias& bias)
      : problem_(problem), data_(data), base_(base), names_(std::move(names)), bounds_(std::move(bounds)),
        bias_(bias) {
    int rows = 0;
    for (const auto* d : data_) rows += static_cast<int>(d->size());
    set_num_residuals(rows);
    mutable_parameter_block_sizes()->assign(
        {static_cast<int>(std::max<std::size_t>(names_.size(), 1)), 1, static_cast<int>(data_.size())});
  }

  Model model(const double* theta, double K) const {
    Model m = base_;
    for (std::size_t i = 0; i < names_.size(); ++i) set_parameter(m.p, names_[i], theta[i]);
    m.p.K = K;
    return m;
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const double* theta = parameters[0];
    const double K = parameters[1][0];
    const double* offsets = parameters[2];
    const Model m = model(theta, K);
    std::vector<std::vector<double>> g;
    problem_.unit_responses(m, g);
    std::vector<double> slope_weight;  // sqrt(h) R'(μ) of each row
    const bool derivatives = jacobians != nullptr;
    if (derivatives) slope_weight.reserve(static_cast<std::size_t>(num_residuals()));
    std::size_t row = 0;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      const auto& d = *data_[j];
      const double weight = std::sqrt(d.h);
      for (std::size_t k = 0; k < d.size(); ++k, ++row) {
        const double mu = d.y0_mm + offsets[j] + K * g[j][k];
        double slope = 0.0;
        const double reading = mu + bias_(mu, slope);
        residuals[row] = weight * (reading - d.y_dwe_mm[k]);
        if (!std::isfinite(residuals[row])) return false;  // Ceres rejects the step
        if (derivatives) slope_weight.push_back(weight * (1.0 + slope));
      }
    }
    if (!derivatives) return true;
    const auto columns = static_cast<std::size_t>(parameter_block_sizes()[0]);
    if (jacobians[0]) theta_columns(theta, K, g, slope_weight, columns, jacobians[0]);
    row = 0;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      for (std::size_t k = 0; k < data_[j]->size(); ++k, ++row) {
        if (jacobians[1]) jacobians[1][row] = slope_weight[row] * g[j][k];
        if (jacobians[2]) {
          double* out = jacobians[2] + row * data_.size();
          std::fill(out, out + data_.size(), 0.0);
          out[j] = slope_weight[row];
        }
      }
    }
    return true;
  }

 private:
  // ∂e/∂θ_i by a forward difference of the response, 1e-7 of the parameter's scale (backward at
  // its upper bound); row-major, `columns` wide.
  void theta_columns(const double* theta, double K, const std::vector<std::vector<double>>& g,
                     const std::vector<double>& slope_weight, std::size_t columns, double* out) const {
    std::fill(out, out + slope_weight.size() * columns, 0.0);
    std::vector<double> moved(theta, theta + columns);
    std::vector<std::vector<double>> g_moved;
    for (std::size_t i = 0; i < names_.size(); ++i) {
      double step = 1e-7 * difference_scale(names_[i], theta[i], data_.front()->h);
      if (theta[i] + step > bounds_[i].second) step = -step;
      moved[i] = theta[i] + step;
      problem_.unit_responses(model(moved.data(), K), g_moved);
      moved[i] = theta[i];
      std::size_t row = 0;
      for (std::size_t j = 0; j < data_.size(); ++j) {
        for (std::size_t k = 0; k < data_[j]->size(); ++k, ++row) {
          out[row * columns + i] = slope_weight[row] * K * (g_moved[j][k] - g[j][k]) / step;
        }
      }
    }
  }

  Problem& problem_;
  const std::vector<const ExperimentData*>& data_;
  Model base_;
  std::vector<std::string> names_;
  std::vector<std::pair<double, double>> bounds_;
  const ReadingBias& bias_;
};

}  // namespace

Model Problem::least_squares_polish(const Model& start, double bracket_s, bool precise, double& best_cost,
                                    bool& converged, std::string& message) {
  // The start: its parameters, with K and the offsets the level's least squares gives them.
  ++evaluations_;
  Model current = start;
  std::vector<std::vector<double>> g;
  unit_responses(current, g);
  linear_gain_and_offsets(current, g);
  std::vector<double> offsets = offsets_;

  std::vector<std::string> names = free_;
  std::vector<double> theta;
  std::vector<std::pair<double, double>> bounds;
  for (const auto& name : names) {
    const auto& spec = options_.bounds[name];
    double lo = spec.lower, hi = spec.upper;
    if (name == "L") {
      const double half_width = bracket_s > 0.0 ? bracket_s : 2.0 * data_.front()->h;
      lo = std::max(lo, start.p.L - half_width);
      hi = std::min(hi, start.p.L + half_width);
    }
    bounds.emplace_back(lo, hi);
    theta.push_back(std::clamp(get_parameter(current.p, name), lo, hi));
  }
  if (theta.empty()) theta.push_back(0.0);  // Ceres needs a non-empty block: a constant one
  double K = current.p.K;

  ReadingResiduals residuals(*this, data_, current, names, bounds, bias_);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem lsq(problem_options);
  lsq.AddResidualBlock(&residuals, nullptr, {theta.data(), &K, offsets.data()});
  if (names.empty()) lsq.SetParameterBlockConstant(theta.data());
  for (std::size_t i = 0; i < names.size(); ++i) {
    lsq.SetParameterLowerBound(theta.data(), static_cast<int>(i), bounds[i].first);
    lsq.SetParameterUpperBound(theta.data(), static_cast<int>(i), bounds[i].second);
  }
  lsq.SetParameterLowerBound(&K, 0, options_.bounds.K.lower);
  lsq.SetParameterUpperBound(&K, 0, options_.bounds.K.upper);

  // Tolerances far below a search's: the cost is the noise floor n σ² plus the misfit, and what
  // separates the optimum from its neighbourhood is a change of about σ², a relative 1/n. The
  // normal equations suffice for the few, Jacobi-scaled columns.
  ceres::Solver::Options solver;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = 50;
  solver.function_tolerance = precise ? 1e-12 : 1e-6;
  solver.parameter_tolerance = precise ? 1e-10 : 1e-6;
  solver.gradient_tolerance = 1e-14;
  solver.logging_type = ceres::SILENT;
  solver.num_threads = 1;
  // Ceres follows each bounded step with a projected line search, a Jacobian per trial; the
  // polish starts inside its bounds near the optimum, where the plain LM step serves.
  solver.max_num_line_search_step_size_iterations = 0;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &lsq, &summary);
  evaluations_ += summary.num_residual_evaluations;

  // Ceres returns the best point it accepted (cost ½ Σ e²), never worse than the start.
  converged = summary.termination_type == ceres::CONVERGENCE;
  message = converged ? "converged" : "least-squares polish: " + summary.message;
  if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) {
    converged = false;
    message = "least-squares polish failed: " + summary.message;
    best_cost = kInf;
    return current;
  }
  best_cost = 2.0 * summary.final_cost;
  offsets_ = offsets;
  return residuals.model(theta.data(), K);
}

}  // namespace canalsim::reduced::detail
