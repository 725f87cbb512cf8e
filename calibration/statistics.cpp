#include "calibration/statistics.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

constexpr double kNullRatio = 1e-9;       // eigenvalue / largest below which a direction is undetermined
constexpr double kHighCorrelation = 0.95;
constexpr double kHighRelativeStd = 0.5;

// The magnitude a parameter's std and sensitivity are relative to: its value, but for a parameter
// searched linearly (offsets, the delay, the zero-head regularisation, openings, the bed slope)
// at least ten finite-difference steps. Those can be zero — clean recordings have offsets near 0
// — and an offset of 1e-4 ± 4e-4 mm is determined to far below the lab's 0.05 mm resolution, not
// "relative std 400 %". The step is the change the parameter's unit resolves (0.05 mm, 0.02 s).
double magnitude(const Parameter& p, double value) {
  return p.transform == Transform::log ? std::abs(value) : std::max(std::abs(value), 10.0 * p.step);
}

// "name" or "ln(name)": the search coordinate of a parameter, in words.
std::string coordinate(const Parameter& p) { return p.transform == Transform::log ? "ln(" + p.name + ")" : p.name; }

// c_a x_a + c_b x_b + ... in words, normalised so that the largest coefficient is 1.
std::string combination(const std::vector<Parameter>& parameters, const std::vector<std::size_t>& which,
                        const std::vector<double>& coefficients) {
  double largest = 0.0;
  for (double c : coefficients) largest = std::max(largest, std::abs(c));
  std::string out;
  for (std::size_t k = 0; k < which.size(); ++k) {
    const double c = coefficients[k] / largest;
    const std::string magnitude = std::abs(std::abs(c) - 1.0) < 5e-3 ? "" : format_g(std::abs(c), 3) + " ";
    if (out.empty()) {
      out = (c < 0 ? "-" : "") + magnitude + coordinate(parameters[which[k]]);
    } else {
      out += (c < 0 ? " - " : " + ") + magnitude + coordinate(parameters[which[k]]);
    }
  }
  return out;
}

}  // namespace

double autocorrelation_inflation(const std::vector<std::vector<double>>& series) {
  double n = 0.0, n_eff = 0.0;
  for (const auto& e : series) {
    if (e.size() < 3) continue;
    const std::size_t m = e.size();
    const double mean = std::accumulate(e.begin(), e.end(), 0.0) / static_cast<double>(m);
    auto autocovariance = [&](std::size_t lag) {
      double c = 0.0;
      for (std::size_t k = 0; k + lag < m; ++k) c += (e[k] - mean) * (e[k + lag] - mean);
      return c / static_cast<double>(m);
    };
    const double c0 = autocovariance(0);
    // Integrated autocorrelation time τ = 1 + 2 Σ ρ_k over the initial positive sequence (sums
    // of adjacent pairs, Geyer 1992), at most a quarter of the series.
    double tau = 1.0;
    if (c0 > 0.0) {
      for (std::size_t lag = 1; lag + 1 < m / 4; lag += 2) {
        const double pair = (autocovariance(lag) + autocovariance(lag + 1)) / c0;
        if (pair <= 0.0) break;
        tau += 2.0 * pair;
      }
    }
    n += static_cast<double>(m);
    n_eff += std::max(1.0, static_cast<double>(m) / tau);
  }
  return n_eff > 0.0 ? std::max(1.0, n / n_eff) : 1.0;
}

ParameterStatistics parameter_statistics(const std::vector<Parameter>& parameters, const std::vector<double>& z,
                                         const std::vector<double>& jacobian, const std::vector<double>& residuals,
                                         const std::vector<std::vector<double>>& series) {
  const auto p = static_cast<Eigen::Index>(parameters.size());
  const auto n = static_cast<Eigen::Index>(residuals.size());
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(jacobian.data(), n, p);
  ParameterStatistics out;
  out.inflation = autocorrelation_inflation(series);
  const double sse = std::inner_product(residuals.begin(), residuals.end(), residuals.begin(), 0.0);
  const double s2 = sse / static_cast<double>(std::max<Eigen::Index>(n - p, 1));

  // Column-scaled normal matrix (unit diagonal) and its eigen-decomposition.
  const Eigen::MatrixXd F = J.transpose() * J;
  Eigen::VectorXd scale(p);
  for (Eigen::Index j = 0; j < p; ++j) scale(j) = F(j, j) > 0.0 ? 1.0 / std::sqrt(F(j, j)) : 0.0;
  const Eigen::MatrixXd Fs = scale.asDiagonal() * F * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Fs);
  const Eigen::VectorXd lambda = eig.eigenvalues();
  const Eigen::MatrixXd V = eig.eigenvectors();
  const double largest = lambda.size() ? lambda.maxCoeff() : 0.0;
  std::vector<bool> undetermined(parameters.size(), false);
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Zero(p, p);
  for (Eigen::Index k = 0; k < p; ++k) {
    if (lambda(k) > kNullRatio * largest && largest > 0.0) {
      inverse += V.col(k) * V.col(k).transpose() / lambda(k);
      continue;
    }
    // A null direction: the parameters it moves are not determined; name them with the
    // combination orthogonal to it (what the data fix), in unscaled search coordinates.
    ParameterStatistics::Unidentified u;
    std::vector<std::size_t> which;
    std::vector<double> null;
    for (Eigen::Index j = 0; j < p; ++j) {
      if (std::abs(V(j, k)) < 0.1) continue;
      undetermined[static_cast<std::size_t>(j)] = true;
      which.push_back(static_cast<std::size_t>(j));
      null.push_back(scale(j) > 0.0 ? V(j, k) * scale(j) : V(j, k));
      u.parameters.push_back(parameters[static_cast<std::size_t>(j)].name);
    }
    u.reason = "exact trade-off: the recordings do not depend on them separately";
    if (which.size() == 2) {
      u.determined = combination(parameters, which, {null[1], -null[0]});
    } else if (which.size() == 1) {
      u.reason = "the recordings do not depend on it";
    } else {
      u.determined = "every combination orthogonal to " + combination(parameters, which, null);
    }
    out.unidentified.push_back(std::move(u));
  }
  // Covariance: the batch-means sandwich (a HAC estimator, e.g. Newey & West 1987; Flegal & Jones
  // 2010 for batch means) B M B with B = (JᵀJ)⁺ and M = Σ_b g_b g_bᵀ, g_b = J_bᵀ r_b summed over
  // blocks of L consecutive samples of one series, L = 2 τ (the integrated autocorrelation time).
  // A residual left by a model that cannot represent the data (another grid, another law) is
  // smooth: its blocks push the parameters the same way, and M grows accordingly; white noise
  // gives back s² B. Scaled by n_b / (n_b − p) for the degrees of freedom.
  const Eigen::MatrixXd B = scale.asDiagonal() * inverse * scale.asDiagonal();
  std::size_t shortest = residuals.size();
  for (const auto& e : series) shortest = std::min(shortest, e.size());
  const std::size_t block = std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(2.0 * out.inflation)), 1,
                                                    std::max<std::size_t>(shortest / 4, 1));
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(p, p);
  std::size_t row = 0, blocks = 0;
  for (const auto& e : series) {
    for (std::size_t start = 0; start < e.size(); start += block) {
      Eigen::VectorXd g = Eigen::VectorXd::Zero(p);
      for (std::size_t k = start; k < std::min(start + block, e.size()); ++k) {
        g += J.row(static_cast<Eigen::Index>(row + k)).transpose() * residuals[row + k];
      }
      M += g * g.transpose();
      ++blocks;
    }
    row += e.size();
  }
  const double dof = static_cast<double>(blocks) / static_cast<double>(std::max<std::size_t>(blocks, parameters.size() + 1) - parameters.size());
  Eigen::MatrixXd Cz = row == residuals.size() ? Eigen::MatrixXd(B * M * B * dof) : Eigen::MatrixXd(s2 * out.inflation * B);
  // Never below the white-noise covariance: the sandwich can be small by chance on few blocks.
  double ratio = 0.0;
  int counted = 0;
  for (Eigen::Index j = 0; j < p; ++j) {
    if (!(B(j, j) > 0.0)) continue;
    ratio += Cz(j, j) / (s2 * B(j, j));
    ++counted;
  }
  ratio = counted ? ratio / counted : 1.0;
  if (ratio < 1.0) Cz = s2 * B;
  out.inflation = std::max(ratio, 1.0);

  const std::size_t np = parameters.size();
  out.std.assign(np, 0.0);
  out.sensitivity.assign(np, 0.0);
  out.correlation.assign(np, std::vector<double>(np, std::numeric_limits<double>::quiet_NaN()));
  for (std::size_t j = 0; j < np; ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    const double value = parameters[j].from_search(z[j]);
    const double sz = std::sqrt(std::max(Cz(jj, jj), 0.0));
    out.std[j] = undetermined[j] ? std::numeric_limits<double>::infinity()
                                 : (parameters[j].transform == Transform::log ? value * sz : sz);
    const double s = parameters[j].transform == Transform::log ? 1.0 : magnitude(parameters[j], value);
    out.sensitivity[j] = std::sqrt(J.col(jj).squaredNorm() / static_cast<double>(std::max<Eigen::Index>(n, 1))) * s;
  }
  for (std::size_t a = 0; a < np; ++a) {
    for (std::size_t b = 0; b < np; ++b) {
      if (undetermined[a] || undetermined[b]) continue;
      const auto ia = static_cast<Eigen::Index>(a), ib = static_cast<Eigen::Index>(b);
      const double d = std::sqrt(Cz(ia, ia) * Cz(ib, ib));
      out.correlation[a][b] = a == b ? 1.0 : (d > 0.0 ? Cz(ia, ib) / d : 0.0);
    }
  }
  // Strong correlations between determined parameters: the pair, and u_a - sign(ρ) u_b with
  // u = z / σ_z, the combination with the small variance.
  for (std::size_t a = 0; a < np; ++a) {
    for (std::size_t b = a + 1; b < np; ++b) {
      const double rho = out.correlation[a][b];
      if (!(std::abs(rho) > kHighCorrelation)) continue;
      const double sa = std::sqrt(Cz(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(a)));
      const double sb = std::sqrt(Cz(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(b)));
      ParameterStatistics::Unidentified u;
      u.parameters = {parameters[a].name, parameters[b].name};
      u.reason = "|correlation| = " + format_fixed(std::abs(rho), 3);
      u.determined = combination(parameters, {a, b}, {1.0 / sa, -(rho > 0 ? 1.0 : -1.0) / sb});
      out.unidentified.push_back(std::move(u));
    }
  }
  for (std::size_t j = 0; j < np; ++j) {
    if (undetermined[j]) continue;
    const double relative = out.std[j] / magnitude(parameters[j], parameters[j].from_search(z[j]));
    if (relative > kHighRelativeStd) {
      ParameterStatistics::Unidentified u;
      u.parameters = {parameters[j].name};
      u.reason = "relative std " + format_fixed(100.0 * relative, 0) + " %";
      u.determined = "not this parameter: the recordings barely depend on it";
      out.unidentified.push_back(std::move(u));
    }
  }
  return out;
}

std::vector<double> optimum_shift(const std::vector<double>& jacobian, const std::vector<double>& change,
                                  std::size_t parameters) {
  const auto p = static_cast<Eigen::Index>(parameters);
  const auto n = static_cast<Eigen::Index>(change.size());
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(jacobian.data(), n, p);
  const Eigen::Map<const Eigen::VectorXd> d(change.data(), n);
  // Complete orthogonal decomposition: the minimum-norm solution when J is rank deficient.
  const Eigen::VectorXd delta = J.completeOrthogonalDecomposition().solve(-d);
  return std::vector<double>(delta.data(), delta.data() + p);
}

}  // namespace canalsim::calibration
