#include "calibration/statistics.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "core/format.hpp"
#include "core/statistics.hpp"

namespace canalsim::calibration {
namespace {

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

// The null directions of the covariance (exact trade-offs): the parameters each moves are not
// determined; named with the combination orthogonal to it (what the data fix), in unscaled search
// coordinates.
void name_null_directions(const std::vector<Parameter>& parameters, const LeastSquaresCovariance& c,
                          ParameterStatistics& out) {
  for (const auto& direction : c.null_directions) {
    ParameterStatistics::Unidentified u;
    std::vector<std::size_t> which;
    std::vector<double> null;
    for (std::size_t j = 0; j < parameters.size(); ++j) {
      if (std::abs(direction[j]) < 0.1) continue;
      which.push_back(j);
      null.push_back(c.column_scale[j] > 0.0 ? direction[j] * c.column_scale[j] : direction[j]);
      u.parameters.push_back(parameters[j].name);
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
}

// Standard deviations in parameter units by the delta method (log: σ_v = v σ_z), and composite
// scaled sensitivities sqrt(Σ_i (J_ij s_j)² / N).
void deviations_and_sensitivities(const std::vector<Parameter>& parameters, const std::vector<double>& z,
                                  const std::vector<double>& jacobian, std::size_t rows,
                                  const LeastSquaresCovariance& c, ParameterStatistics& out) {
  const auto p = static_cast<Eigen::Index>(parameters.size());
  const auto n = static_cast<Eigen::Index>(rows);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(jacobian.data(), n, p);
  const std::vector<double> sz = standard_deviations(c);
  out.std.assign(parameters.size(), 0.0);
  out.sensitivity.assign(parameters.size(), 0.0);
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    const auto jj = static_cast<Eigen::Index>(j);
    const double value = parameters[j].from_search(z[j]);
    const bool log = parameters[j].transform == Transform::log;
    out.std[j] = c.undetermined[j] || !log ? sz[j] : value * sz[j];
    const double s = log ? 1.0 : magnitude(parameters[j], value);
    out.sensitivity[j] = std::sqrt(J.col(jj).squaredNorm() / static_cast<double>(std::max<Eigen::Index>(n, 1))) * s;
  }
}

// Strong correlations between determined parameters: the pair, and u_a - sign(ρ) u_b with
// u = z / σ_z, the combination with the small variance.
void name_strong_correlations(const std::vector<Parameter>& parameters, const LeastSquaresCovariance& c,
                              ParameterStatistics& out) {
  const std::size_t np = parameters.size();
  for (std::size_t a = 0; a < np; ++a) {
    for (std::size_t b = a + 1; b < np; ++b) {
      const double rho = out.correlation[a][b];
      if (!(std::abs(rho) > kHighCorrelation)) continue;
      const double sa = std::sqrt(c(a, a));
      const double sb = std::sqrt(c(b, b));
      ParameterStatistics::Unidentified u;
      u.parameters = {parameters[a].name, parameters[b].name};
      u.reason = "|correlation| = " + format_fixed(std::abs(rho), 3);
      u.determined = combination(parameters, {a, b}, {1.0 / sa, -(rho > 0 ? 1.0 : -1.0) / sb});
      out.unidentified.push_back(std::move(u));
    }
  }
}

// Determined parameters whose relative std exceeds kHighRelativeStd.
void name_weak_parameters(const std::vector<Parameter>& parameters, const std::vector<double>& z,
                          const LeastSquaresCovariance& c, ParameterStatistics& out) {
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    if (c.undetermined[j]) continue;
    const double relative = out.std[j] / magnitude(parameters[j], parameters[j].from_search(z[j]));
    if (relative > kHighRelativeStd) {
      ParameterStatistics::Unidentified u;
      u.parameters = {parameters[j].name};
      u.reason = "relative std " + format_fixed(100.0 * relative, 0) + " %";
      u.determined = "not this parameter: the recordings barely depend on it";
      out.unidentified.push_back(std::move(u));
    }
  }
}

}  // namespace

ParameterStatistics parameter_statistics(const std::vector<Parameter>& parameters, const std::vector<double>& z,
                                         const std::vector<double>& jacobian, const std::vector<double>& residuals,
                                         const std::vector<std::vector<double>>& series) {
  // The covariance in the search coordinates: the batch-means sandwich of core/statistics.hpp.
  const LeastSquaresCovariance c = least_squares_covariance(jacobian, parameters.size(), residuals, series);
  ParameterStatistics out;
  out.inflation = c.inflation;
  name_null_directions(parameters, c, out);
  deviations_and_sensitivities(parameters, z, jacobian, residuals.size(), c, out);
  out.correlation = correlations(c);
  name_strong_correlations(parameters, c, out);
  name_weak_parameters(parameters, z, c, out);
  return out;
}

}  // namespace canalsim::calibration
