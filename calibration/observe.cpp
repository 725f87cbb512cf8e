#include "calibration/observe.hpp"

#include <cmath>

#include "core/laws.hpp"
#include "core/recording.hpp"

namespace canalsim::calibration {
namespace {

// Linear interpolation of a uniformly sampled series at a fractional index (clamped at the ends:
// before the first sample the experiment was at its steady state).
double at_fractional(const std::vector<double>& y, double index) {
  if (index <= 0.0) return y.front();
  const double last = static_cast<double>(y.size() - 1);
  if (index >= last) return y.back();
  const auto k = static_cast<std::size_t>(index);
  const double f = index - static_cast<double>(k);
  return y[k] + f * (y[k + 1] - y[k]);
}

}  // namespace

bool is_level(const std::string& channel) {
  return channel == columns::upstream_level || channel == columns::level_below_gate ||
         channel == columns::level_downstream_end || channel.rfind("y_check", 0) == 0;
}

SensorModel sensor_model_of(const scenarios::SensorSpec& sensors) {
  SensorModel m{sensors.resolution_mm, sensors.delay_s, sensors.offset_mm};
  if (sensors.offset_y_up_mm != 0.0) m.channel_offset_mm[columns::upstream_level] = sensors.offset_y_up_mm;
  if (sensors.offset_y_dw_mm != 0.0) m.channel_offset_mm[columns::level_below_gate] = sensors.offset_y_dw_mm;
  if (sensors.offset_y_dwe_mm != 0.0) m.channel_offset_mm[columns::level_downstream_end] = sensors.offset_y_dwe_mm;
  return m;
}

double expected_reading(double y, double resolution, double spread) {
  if (!(resolution > 0.0)) return y;
  if (!(spread > 0.0)) return resolution * std::round(y / resolution);
  const double r = resolution;
  // Above two steps of spread the reading is unbiased to machine precision: the bias is a Fourier
  // series in y / r whose largest term is (r / π) exp(-2π² spread² / r²) < 1e-35 r (Widrow &
  // Kollár 2008, Quantization Noise, ch. 4). Summing would also take 16 spread / r terms: 10⁹ for
  // a level spike of 1e9 mm.
  if (spread > 2.0 * r) return y;
  const auto first = static_cast<long>(std::floor((y - 8.0 * spread) / r)) - 1;
  const auto last = static_cast<long>(std::ceil((y + 8.0 * spread) / r)) + 1;
  auto cdf = [&](double v) { return 0.5 * std::erfc(-(v - y) / (spread * std::sqrt(2.0))); };
  double sum = 0.0;
  for (long m = first; m <= last; ++m) {
    const double level = static_cast<double>(m) * r;
    sum += level * (cdf(level + 0.5 * r) - cdf(level - 0.5 * r));
  }
  return sum;
}

Channels observe(const Channels& truth, const SensorModel& m, double period_s) {
  Channels out;
  const double clock_shift = m.clock_delay_s / period_s;
  static const ChannelFault kHealthy;
  for (const auto& [name, y] : truth) {
    std::vector<double> v(y.size());
    if (!is_level(name)) {
      for (std::size_t k = 0; k < y.size(); ++k) v[k] = clock_shift == 0.0 ? y[k] : at_fractional(y, static_cast<double>(k) - clock_shift);
      out[name] = std::move(v);
      continue;
    }
    const auto own = m.channel_offset_mm.find(name);
    const auto found = m.channel_fault.find(name);
    const ChannelFault& fault = found == m.channel_fault.end() ? kHealthy : found->second;
    const double offset = m.offset_mm + (own == m.channel_offset_mm.end() ? 0.0 : own->second) + fault.offset_mm;
    const double shift = clock_shift + (m.delay_s + fault.delay_s) / period_s;
    const double resolution = fault.resolution_mm >= 0.0 ? fault.resolution_mm : m.resolution_mm;
    const double drift_per_sample = fault.drift_mm_per_min * period_s / 60.0;
    for (std::size_t k = 0; k < y.size(); ++k) {
      const double level = fault.gain * at_fractional(y, static_cast<double>(k) - shift) + offset +
                           drift_per_sample * static_cast<double>(k) - fault.lattice_offset_mm;
      v[k] = fault.lattice_offset_mm +
             (m.reading_spread_mm > 0.0 ? expected_reading(level, resolution, m.reading_spread_mm)
                                        : laws::quantise(level, resolution));
    }
    out[name] = std::move(v);
  }
  return out;
}

}  // namespace canalsim::calibration
