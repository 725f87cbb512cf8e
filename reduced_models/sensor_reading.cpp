#include "reduced_models/sensor_reading.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace canalsim::reduced {

SensorLattice recorded_lattice(const std::vector<const ExperimentData*>& data) {
  std::vector<double> values;
  for (const auto* d : data) values.insert(values.end(), d->y_dwe_mm.begin(), d->y_dwe_mm.end());
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  if (sorted.size() < 3) return {};
  std::vector<double> gaps;
  for (std::size_t i = 1; i < sorted.size(); ++i) gaps.push_back(sorted[i] - sorted[i - 1]);
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 10), gaps.end());
  const double step = gaps[gaps.size() / 10];
  if (!(step > 1e-9)) return {};
  std::complex<double> phase = 0.0;
  for (double y : values) phase += std::polar(1.0, 2.0 * std::numbers::pi * y / step);
  double origin = step * std::arg(phase) / (2.0 * std::numbers::pi);
  if (origin < 0.0) origin += step;
  std::size_t on = 0;
  for (double y : values) {
    const double m = (y - origin) / step;
    on += std::abs(m - std::round(m)) < 0.01 ? 1 : 0;
  }
  if (static_cast<double>(on) < 0.95 * static_cast<double>(values.size())) return {};
  return {step, origin};
}

double ReadingBias::operator()(double mu, double& derivative) const {
  derivative = 0.0;
  const double r = lattice.step;
  if (!(r > 0.0)) return 0.0;
  const double ratio = sigma / r;
  const double phase = 2.0 * std::numbers::pi * (mu - lattice.origin) / r;
  double b = 0.0;
  // Terms until the noise damps them below 1e-6 r (σ/r = 0.3: two terms; at most 50).
  for (int m = 1; m <= 50; ++m) {
    const double damping = std::exp(-2.0 * std::numbers::pi * std::numbers::pi * m * m * ratio * ratio);
    if (damping < 1e-6) break;
    const double sign = m % 2 == 1 ? 1.0 : -1.0;
    b -= r / (std::numbers::pi * m) * sign * damping * std::sin(m * phase);
    derivative -= 2.0 * sign * damping * std::cos(m * phase);
  }
  return b;
}

}  // namespace canalsim::reduced
