// The Cramér–Rao bound of a first-order-plus-delay step response observed through a noisy,
// quantising level sensor, computed from first principles (independent of the fitter).
//
// Observation model: y_k = Q(μ_k(θ) + e_k), e_k ~ N(0, σ²) independent, Q the sensor's
// quantiser with resolution r on a lattice offset by o (Q(x) = r·nint((x − o)/r) + o; r = 0: no
// quantiser). μ_k(θ) = y0 + K A (1 − e^{−τ_k/T}) for τ_k = t_k − t_step − L > 0, else y0.
//
// The Fisher information of one quantised sample about its mean μ is (bins j = [l_j, u_j))
//     I(μ) = Σ_j (φ(a_j) − φ(b_j))² / (σ² P_j),  a_j = (l_j − μ)/σ, b_j = (u_j − μ)/σ,
//     P_j = Φ(b_j) − Φ(a_j),
// (σ⁻² without the quantiser), and the Fisher matrix of θ is F = Σ_k I(μ_k) ∇μ_k ∇μ_kᵀ; the
// bound on the variance of any unbiased estimate of θ_i is (F⁻¹)_ii. θ = (K, T, L) or, with the
// operating point y0 estimated jointly, (K, T, L, y0).
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace canalsim::testing_crb {

struct FopdtExperiment {
  double K, T, L;       // the truth
  double A = 5.0;       // step of the command, mm
  double t_step = 0.0;  // s
  double h = 0.125;     // sampling period, s
  std::size_t n = 0;    // samples
  double sigma = 0.03;  // noise std, mm
  double quantum = 0.1; // sensor resolution r, mm (0 = none)
  double quantum_offset = 0.037;
  double y0 = 45.0;
};

inline double normal_pdf(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi); }
inline double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

// Fisher information of one sample about its mean μ.
inline double sample_information(double mu, double sigma, double r, double offset) {
  if (r <= 0.0) return 1.0 / (sigma * sigma);
  const double centre = r * std::round((mu - offset) / r) + offset;
  const int reach = static_cast<int>(std::ceil(8.0 * sigma / r)) + 1;
  double info = 0.0;
  for (int j = -reach; j <= reach; ++j) {
    const double q = centre + j * r;
    const double a = (q - 0.5 * r - mu) / sigma, b = (q + 0.5 * r - mu) / sigma;
    const double p = normal_cdf(b) - normal_cdf(a);
    if (p < 1e-300) continue;
    const double dp = normal_pdf(a) - normal_pdf(b);
    info += dp * dp / (sigma * sigma * p);
  }
  return info;
}

// The Fisher matrix of (K, T, L[, y0]).
inline Eigen::MatrixXd fisher_matrix(const FopdtExperiment& e, bool with_operating_point) {
  const int p = with_operating_point ? 4 : 3;
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd g(p);
  for (std::size_t k = 0; k < e.n; ++k) {
    const double tau = static_cast<double>(k) * e.h - e.t_step - e.L;
    g.setZero();
    double mu = e.y0;
    if (tau > 0.0) {
      const double decay = std::exp(-tau / e.T);
      mu += e.K * e.A * (1.0 - decay);
      g(0) = e.A * (1.0 - decay);
      g(1) = -e.K * e.A * decay * tau / (e.T * e.T);
      g(2) = -e.K * e.A * decay / e.T;
    }
    if (with_operating_point) g(3) = 1.0;
    F += sample_information(mu, e.sigma, e.quantum, e.quantum_offset) * g * g.transpose();
  }
  return F;
}

// Standard deviations bounding unbiased estimates of (K, T, L[, y0]).
inline Eigen::VectorXd crb_std(const FopdtExperiment& e, bool with_operating_point) {
  return fisher_matrix(e, with_operating_point).inverse().diagonal().cwiseSqrt();
}

}  // namespace canalsim::testing_crb
