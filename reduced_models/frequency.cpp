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
  const Complex delayed_gain = linearised_gain(m, op) * std::exp(-s * p.L);
  // (iω)^λ on the principal branch.
  const auto fractional_lag = [&](double lambda) {
    return p.T * std::pow(omega, lambda) * std::exp(Complex(0.0, lambda * M_PI / 2.0)) + 1.0;
  };
  switch (m.kind) {  // no default: a new model kind must say its transfer function here
    case ModelKind::sopd: return delayed_gain / ((p.T * s + 1.0) * (p.T2 * s + 1.0));
    case ModelKind::liom:
    case ModelKind::nliom_f:
    case ModelKind::nliom_s: return delayed_gain / (p.T * s + 1.0);
    case ModelKind::lfom:
    case ModelKind::nlfom_f:
    case ModelKind::nlfom_s:
    case ModelKind::hybrid: return delayed_gain / fractional_lag(p.lambda);
  }
  return {NAN, NAN};
}

}  // namespace canalsim::reduced
