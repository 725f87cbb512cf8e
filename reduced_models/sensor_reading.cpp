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

ReadingBias::ReadingBias(SensorLattice lattice, double sigma) : lattice_(lattice), sigma_(sigma) {
  const double r = lattice.step;
  if (!(r > 0.0)) return;
  const double ratio = sigma / r, pi = std::numbers::pi;
  // The series' terms until the noise damps them below 1e-6 (σ/r = 0.3: two terms; at most 50).
  std::vector<double> amplitude;  // of sin(m θ) in b, θ = 2π (μ − o)/r
  for (int m = 1; m <= 50; ++m) {
    const double damping = std::exp(-2.0 * pi * pi * m * m * ratio * ratio);
    if (damping < 1e-6) break;
    amplitude.push_back(-r / (pi * m) * (m % 2 == 1 ? 1.0 : -1.0) * damping);
  }
  if (amplitude.empty()) return;  // so much noise that the reading is the level: b = 0
  const double dtheta = 2.0 * pi / r;  // dθ/dμ
  for (std::size_t i = 0; i <= kNodes; ++i) {
    const double theta = 2.0 * pi * static_cast<double>(i) / static_cast<double>(kNodes);
    double b = 0.0, db = 0.0, d2b = 0.0;
    for (std::size_t t = 0; t < amplitude.size(); ++t) {
      const double m = static_cast<double>(t + 1), w = m * dtheta;
      b += amplitude[t] * std::sin(m * theta);
      db += amplitude[t] * w * std::cos(m * theta);
      d2b -= amplitude[t] * w * w * std::sin(m * theta);
    }
    value_.push_back(b);
    slope_.push_back(db);
    curvature_.push_back(d2b);
  }
}

double ReadingBias::operator()(double mu, double& derivative) const {
  derivative = 0.0;
  if (value_.empty()) return 0.0;
  // The node interval holding μ and the position s ∈ [0, 1) in it.
  const double position = (mu - lattice_.origin) / lattice_.step * static_cast<double>(kNodes);
  const double cell = std::floor(position);
  const double s = position - cell;
  auto i = static_cast<long>(cell) % static_cast<long>(kNodes);
  if (i < 0) i += static_cast<long>(kNodes);
  const auto a = static_cast<std::size_t>(i);
  const double spacing = lattice_.step / static_cast<double>(kNodes);  // in μ
  // Cubic Hermite basis on [0, 1].
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2.0 * s3 - 3.0 * s2 + 1.0, h10 = s3 - 2.0 * s2 + s, h01 = -2.0 * s3 + 3.0 * s2,
               h11 = s3 - s2;
  derivative = h00 * slope_[a] + h10 * spacing * curvature_[a] + h01 * slope_[a + 1] + h11 * spacing * curvature_[a + 1];
  return h00 * value_[a] + h10 * spacing * slope_[a] + h01 * value_[a + 1] + h11 * spacing * slope_[a + 1];
}

}  // namespace canalsim::reduced
