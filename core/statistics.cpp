#include "core/statistics.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace canalsim {
namespace {

using RowMajorMap = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;

constexpr double kNullRatio = 1e-9;  // eigenvalue / largest below which a direction is undetermined
constexpr double kNullComponent = 0.1;  // a null direction's component above which it moves a parameter

// B = (JᵀJ)⁺ by the eigen-decomposition of the column-scaled JᵀJ (unit diagonal), dropping the
// directions whose eigenvalue is below kNullRatio of the largest; those are recorded in `out`.
Eigen::MatrixXd scaled_pseudo_inverse(const RowMajorMap& J, LeastSquaresCovariance& out) {
  const Eigen::Index p = J.cols();
  const Eigen::MatrixXd F = J.transpose() * J;
  Eigen::VectorXd scale(p);
  for (Eigen::Index j = 0; j < p; ++j) scale(j) = F(j, j) > 0.0 ? 1.0 / std::sqrt(F(j, j)) : 0.0;
  const Eigen::MatrixXd Fs = scale.asDiagonal() * F * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Fs);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const Eigen::MatrixXd V = eig.eigenvectors();
  const double largest = lambda.size() ? lambda.maxCoeff() : 0.0;
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Zero(p, p);
  for (Eigen::Index k = 0; k < p; ++k) {
    if (lambda(k) > kNullRatio * largest && largest > 0.0) {
      inverse += V.col(k) * V.col(k).transpose() / lambda(k);
      continue;
    }
    out.null_directions.emplace_back(V.col(k).data(), V.col(k).data() + p);
    for (Eigen::Index j = 0; j < p; ++j) {
      if (!(std::abs(V(j, k)) < kNullComponent)) out.undetermined[static_cast<std::size_t>(j)] = true;
    }
  }
  out.column_scale.assign(scale.data(), scale.data() + p);
  return scale.asDiagonal() * inverse * scale.asDiagonal();
}

// M = Σ_b g_b g_bᵀ, g_b = J_bᵀ r_b over blocks of `block` consecutive samples of each series;
// `blocks` counts them. The caller checks that the series split the rows.
Eigen::MatrixXd block_score_products(const RowMajorMap& J, const std::vector<double>& residuals,
                                     const std::vector<std::vector<double>>& series, std::size_t block,
                                     std::size_t& rows, std::size_t& blocks) {
  const Eigen::Index p = J.cols();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(p, p);
  rows = 0;
  blocks = 0;
  for (const auto& e : series) {
    for (std::size_t start = 0; start < e.size(); start += block) {
      Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
      for (std::size_t k = start; k < std::min(start + block, e.size()); ++k) {
        g += J.row(static_cast<Eigen::Index>(rows + k)).transpose() * residuals[rows + k];
      }
      M += g * g.transpose();
      ++blocks;
    }
    rows += e.size();
  }
  return M;
}

}  // namespace

std::vector<double> autocorrelation(const std::vector<double>& series, int max_lag) {
  const double mean = series.empty() ? 0.0 : std::accumulate(series.begin(), series.end(), 0.0) / static_cast<double>(series.size());
  std::vector<double> x(series.size());
  double r0 = 0.0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    x[k] = series[k] - mean;
    r0 += x[k] * x[k];
  }
  std::vector<double> r(static_cast<std::size_t>(std::max(max_lag, 0)) + 1, 0.0);
  if (r0 <= 0.0) return r;
  for (std::size_t k = 0; k < r.size() && k < x.size(); ++k) {
    double s = 0.0;
    for (std::size_t t = 0; t + k < x.size(); ++t) s += x[t] * x[t + k];
    r[k] = s / r0;
  }
  return r;
}

double integrated_autocorrelation_time(const std::vector<double>& e) {
  const std::size_t m = e.size();
  if (m < 3) return 1.0;
  const double mean = std::accumulate(e.begin(), e.end(), 0.0) / static_cast<double>(m);
  auto autocovariance = [&](std::size_t lag) {
    double c = 0.0;
    for (std::size_t k = 0; k + lag < m; ++k) c += (e[k] - mean) * (e[k + lag] - mean);
    return c / static_cast<double>(m);
  };
  const double c0 = autocovariance(0);
  // Sums of adjacent pairs ρ_k + ρ_{k+1} stay positive for a reversible chain's autocorrelation
  // (Geyer 1992): the first non-positive pair ends the sum, before the noise of the far lags.
  double tau = 1.0;
  if (c0 > 0.0) {
    for (std::size_t lag = 1; lag + 1 < m / 4; lag += 2) {
      const double pair = (autocovariance(lag) + autocovariance(lag + 1)) / c0;
      if (pair <= 0.0) break;
      tau += 2.0 * pair;
    }
  }
  return tau;
}

double autocorrelation_inflation(const std::vector<std::vector<double>>& series) {
  double n = 0.0, n_eff = 0.0;
  for (const auto& e : series) {
    if (e.size() < 3) continue;
    const auto m = static_cast<double>(e.size());
    n += m;
    n_eff += std::max(1.0, m / integrated_autocorrelation_time(e));
  }
  return n_eff > 0.0 ? std::max(1.0, n / n_eff) : 1.0;
}

LeastSquaresCovariance least_squares_covariance(const std::vector<double>& jacobian, std::size_t np,
                                                const std::vector<double>& residuals,
                                                const std::vector<std::vector<double>>& series) {
  const auto p = static_cast<Eigen::Index>(np);
  const auto n = static_cast<Eigen::Index>(residuals.size());
  const RowMajorMap J(jacobian.data(), n, p);
  LeastSquaresCovariance out;
  out.parameters = np;
  out.undetermined.assign(np, false);
  const double inflation = autocorrelation_inflation(series);
  const double sse = std::inner_product(residuals.begin(), residuals.end(), residuals.begin(), 0.0);
  const double s2 = sse / static_cast<double>(std::max<Eigen::Index>(n - p, 1));

  const Eigen::MatrixXd B = scaled_pseudo_inverse(J, out);

  // The sandwich over blocks of L = 2τ samples of one series: a smooth residual's blocks push the
  // parameters the same way and M grows accordingly; white noise gives back s² B.
  std::size_t shortest = residuals.size();
  for (const auto& e : series) shortest = std::min(shortest, e.size());
  const std::size_t block = std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(2.0 * inflation)), 1,
                                                    std::max<std::size_t>(shortest / 4, 1));
  std::size_t rows = 0, blocks = 0;
  const Eigen::MatrixXd M = block_score_products(J, residuals, series, block, rows, blocks);
  const double dof = static_cast<double>(blocks) / static_cast<double>(std::max<std::size_t>(blocks, np + 1) - np);
  Eigen::MatrixXd C = rows == residuals.size() ? Eigen::MatrixXd(B * M * B * dof) : Eigen::MatrixXd(s2 * inflation * B);

  // Never below the white-noise covariance: the sandwich can be small by chance on few blocks.
  double ratio = 0.0;
  int counted = 0;
  for (Eigen::Index j = 0; j < p; ++j) {
    if (!(B(j, j) > 0.0)) continue;
    ratio += C(j, j) / (s2 * B(j, j));
    ++counted;
  }
  ratio = counted ? ratio / counted : 1.0;
  if (ratio < 1.0) C = s2 * B;
  out.inflation = std::max(ratio, 1.0);
  out.matrix.resize(np * np);
  for (std::size_t a = 0; a < np; ++a) {
    for (std::size_t b = 0; b < np; ++b) out.matrix[a * np + b] = C(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
  }
  return out;
}

std::vector<double> standard_deviations(const LeastSquaresCovariance& c) {
  std::vector<double> out(c.parameters);
  for (std::size_t j = 0; j < c.parameters; ++j) {
    out[j] = c.undetermined[j] ? std::numeric_limits<double>::infinity() : std::sqrt(std::max(c(j, j), 0.0));
  }
  return out;
}

std::vector<std::vector<double>> correlations(const LeastSquaresCovariance& c) {
  const std::size_t np = c.parameters;
  std::vector<std::vector<double>> out(np, std::vector<double>(np, std::numeric_limits<double>::quiet_NaN()));
  for (std::size_t a = 0; a < np; ++a) {
    for (std::size_t b = 0; b < np; ++b) {
      if (c.undetermined[a] || c.undetermined[b]) continue;
      const double d = std::sqrt(c(a, a) * c(b, b));
      out[a][b] = a == b ? 1.0 : (d > 0.0 ? c(a, b) / d : 0.0);
    }
  }
  return out;
}

std::vector<double> optimum_shift(const std::vector<double>& jacobian, const std::vector<double>& change,
                                  std::size_t parameters) {
  const auto p = static_cast<Eigen::Index>(parameters);
  const auto n = static_cast<Eigen::Index>(change.size());
  const RowMajorMap J(jacobian.data(), n, p);
  const Eigen::Map<const Eigen::VectorXd> d(change.data(), n);
  // δ = −(JᵀJ)⁺ Jᵀ d with the covariance's pseudo-inverse: the directions the Jacobian does not
  // determine are left unmoved (the minimum-norm solution in the column-scaled coordinates).
  LeastSquaresCovariance scratch;
  scratch.undetermined.assign(parameters, false);
  const Eigen::VectorXd delta = -scaled_pseudo_inverse(J, scratch) * (J.transpose() * d);
  return std::vector<double>(delta.data(), delta.data() + p);
}

}  // namespace canalsim
