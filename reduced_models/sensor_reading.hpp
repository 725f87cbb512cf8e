// What a quantising level sensor reads, for the least-squares polish of a fit
// (identification.hpp, Criterion::least_squares).
//
// A sensor of resolution r whose lattice is offset by o reads Q(x) = o + r·nint((x − o)/r) of the
// level plus its noise, x = μ + e, e ~ N(0, σ²). When σ is not large against r (σ/r = 0.3 at the
// paper's 0.05 mm and a quiet ultrasonic sensor) the reading is not dithered: its mean is
// E[Q(μ + e)] = μ + b(μ) with the periodic bias (the sawtooth Q(x) − x in Fourier series,
// each term damped by the noise's characteristic function)
//
//     b(μ) = −Σ_{m≥1} (r/(π m)) (−1)^{m+1} e^{−2π² m² σ²/r²} sin(2π m (μ − o)/r),
//
// up to ±0.17 r/π at σ/r = 0.3. Least squares on μ is then biased where the level moves slowly
// through the lattice: the first millimetres of a slow pool's rise, i.e. its delay (a T = 60 s
// pool at 100 Hz: +0.02 s, twice its Cramér–Rao bound). Fitting E[Q(μ + e)] instead removes it.
#pragma once

#include <vector>

#include "reduced_models/data.hpp"

namespace canalsim::reduced {

struct SensorLattice {
  double step = 0.0;    // r, mm; 0: the recorded levels lie on no lattice
  double origin = 0.0;  // o in [0, r)
};

// The lattice the recorded levels y_dwe lie on: the step is a low quantile (10 %) of the spacings
// between distinct values, accepted when at least 95 % of the samples lie within a hundredth of
// it from the lattice through the origin given by the circular mean of the phases
// arg Σ exp(2πi y / r). (The same rule as the diagnosis' sensor_quantization effect.)
SensorLattice recorded_lattice(const std::vector<const ExperimentData*>& data);

// b(μ) above and its derivative b'(μ), for noise σ (mm). b is periodic in μ: it is summed once on
// kNodes points of a period (with b' and b'') and read by cubic Hermite interpolation, so that a
// least-squares polish that reads every sample at every evaluation pays a few multiply-adds, not
// a sine and a cosine per term (the interpolation error is below 1e-6 of b's amplitude: the
// sharpest term the noise leaves, m = 17 at σ/r = 0.05, spans 60 nodes).
class ReadingBias {
 public:
  ReadingBias() = default;  // no lattice: b = 0
  ReadingBias(SensorLattice lattice, double sigma);

  const SensorLattice& lattice() const { return lattice_; }
  double sigma() const { return sigma_; }
  double operator()(double mu, double& derivative) const;

 private:
  static constexpr std::size_t kNodes = 1024;
  SensorLattice lattice_;
  double sigma_ = 0.0;
  // b, b' and b'' at μ = o + r i / kNodes, i = 0 … kNodes (the last repeats the first).
  std::vector<double> value_, slope_, curvature_;
};

}  // namespace canalsim::reduced
