// The reduced models' frequency responses (reduced_models/frequency.hpp) against their own
// time-domain simulation (Grünwald–Letnikov, full memory): a sine command, the periodic response
// fitted by least squares, compared in gain and phase.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include <Eigen/Dense>

#include "reduced_models/frequency.hpp"

namespace canalsim::reduced {
namespace {

// Gain and phase of the simulated Δy for Δu = a sin ωt (after 10 T of transient).
std::complex<double> simulated(const Model& model, double omega, double y_up_mm) {
  ExperimentData d;
  d.source = "sine";
  d.h = 0.005;
  d.u0_mm = 25.0;
  d.y0_mm = 40.0;
  const double amplitude = 0.5, settle = 60.0, period = 2.0 * M_PI / omega;
  const double end = settle + period * std::ceil(40.0 / period);
  for (double t = 0.0; t < end; t += d.h) {
    d.t_s.push_back(t);
    d.u_mm.push_back(d.u0_mm + amplitude * std::sin(omega * t));
    d.y_dwe_mm.push_back(d.y0_mm);
    d.y_up_mm.push_back(y_up_mm);
  }
  SimulationOptions options;
  options.gl.memory = GlMemory::full;
  const auto y = simulate(model, d, options).y_dwe_mm;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < y.size(); ++k) {
    if (d.t_s[k] < settle) continue;
    const Eigen::Vector3d basis(1.0, std::sin(omega * d.t_s[k]), std::cos(omega * d.t_s[k]));
    m += basis * basis.transpose();
    rhs += basis * (y[k] - d.y0_mm);
  }
  const Eigen::Vector3d c = m.ldlt().solve(rhs);
  return std::complex<double>(c(1), c(2)) / amplitude;
}

TEST(FrequencyResponse, MatchesTheModelsSimulatedResponseToSines) {
  std::vector<Model> models(3);
  models[0].kind = ModelKind::liom;
  models[0].p = {0.5, 3.0, 0.5, 1.0, 0.5, 1.0};
  models[1].kind = ModelKind::lfom;
  models[1].p = {0.5, 3.0, 0.5, 0.6, 0.5, 1.0};
  models[2].kind = ModelKind::nlfom_f;  // linearised: K (y_up/H)^γ = 0.5 (60/50)^2
  models[2].p = {0.5, 3.0, 0.5, 0.6, 2.0, 1.0};
  models[2].p.head_ref_mm = 50.0;
  const OperatingPoint point{25.0, 40.0, 60.0};
  EXPECT_DOUBLE_EQ(linearised_gain(models[2], point), 0.5 * 1.44);
  for (const Model& model : models) {
    for (double omega : {0.1, 0.5, 2.0}) {
      const auto expected = frequency_response(model, point, omega);
      const auto got = simulated(model, omega, 60.0);
      EXPECT_NEAR(std::abs(got) / std::abs(expected), 1.0, 0.01) << model_name(model.kind) << " at " << omega;
      EXPECT_LT(std::abs(std::arg(got / expected)) * 180.0 / M_PI, 1.0) << model_name(model.kind) << " at " << omega;
    }
  }
}

}  // namespace
}  // namespace canalsim::reduced
