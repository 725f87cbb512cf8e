// Frequency responses of the reduced models (models.hpp) about an operating point, in mm of
// y_dwe per mm of gate command, to hold them against the linearised Saint-Venant pool
// (linearize/, docs/linearization.md §7):
//
//   LIOM  K e^{−iωL} / (T iω + 1)              SOPD  K e^{−iωL} / ((T iω + 1)(T2 iω + 1))
//   LFOM  K e^{−iωL} / (T (iω)^λ + 1)          ((iω)^λ = ω^λ e^{iλπ/2}, the principal branch)
//
// The nonlinear models are linearised at the operating point (u0, y0, y_up): their input term
// g(t) Δu(t − L) has Δu = 0 there, so a small change of the head inside g multiplies a zero input
// and only g's value at the operating point remains: K (y_up/H)^γ (free flow, eqs. 12–13) or
// K ((y_up − y0)/H)^γ (submerged, eqs. 14–15; the hybrid takes the term of its regime at the
// operating point). The rate limit (eq. 16) is inactive for small inputs and the quantisation
// (eq. 17) is not differentiable: neither enters.
#pragma once

#include <complex>

#include "reduced_models/models.hpp"

namespace canalsim::reduced {

struct OperatingPoint {
  double u0_mm = 0.0;
  double y0_mm = 0.0;
  double y_up_mm = 0.0;  // used by the nonlinear models only
};

// The static gain of the linearised input term, mm/mm (K for the linear models).
double linearised_gain(const Model& model, const OperatingPoint& point);
std::complex<double> frequency_response(const Model& model, const OperatingPoint& point, double omega);

}  // namespace canalsim::reduced
