#include "reduced_models/frequency.hpp"

#include <algorithm>
#include <cmath>

namespace canalsim::reduced {
namespace {

// (head / H)^γ with H = 0 read as "H = the head" (the model's reference not yet set).
double head_factor(double head_mm, double reference_mm, double gamma) {
  const double head = std::max(head_mm, 0.0);
  return std::pow(reference_mm > 0.0 ? head / reference_mm : 1.0, gamma);
}

}  // namespace

double linearised_gain(const Model& m, const OperatingPoint& op) {
  const ModelParameters& p = m.p;
  const double free_head = op.y_up_mm, submerged_head = op.y_up_mm - op.y0_mm;
  switch (m.kind) {
    case ModelKind::liom:
    case ModelKind::sopd:
    case ModelKind::lfom: return p.K;
    case ModelKind::nliom_f:
    case ModelKind::nlfom_f: return p.K * head_factor(free_head, p.head_ref_mm, p.gamma);
    case ModelKind::nliom_s:
    case ModelKind::nlfom_s: return p.K * head_factor(submerged_head, p.head_ref_mm, p.gamma);
    case ModelKind::hybrid:
      return is_free_flow(op.y_up_mm, op.y0_mm, op.u0_mm)
                 ? p.K * head_factor(free_head, p.head_ref_mm, p.gamma)
                 : p.K_sub * head_factor(submerged_head, p.head_ref_sub_mm, p.gamma_sub);
  }
  return p.K;
}

std::complex<double> frequency_response(const Model& m, const OperatingPoint& op, double omega) {
  using Complex = std::complex<double>;
  const ModelParameters& p = m.p;
  const Complex s(0.0, omega);
  const Complex delay = std::exp(-s * p.L);
  const double gain = linearised_gain(m, op);
  if (m.kind == ModelKind::sopd) return gain * delay / ((p.T * s + 1.0) * (p.T2 * s + 1.0));
  const double lambda = is_fractional(m.kind) ? p.lambda : 1.0;
  const Complex s_lambda = std::pow(omega, lambda) * std::exp(Complex(0.0, lambda * M_PI / 2.0));
  return gain * delay / (p.T * s_lambda + 1.0);
}

}  // namespace canalsim::reduced
