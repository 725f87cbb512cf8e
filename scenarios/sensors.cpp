#include "scenarios/sensors.hpp"

#include "core/laws.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace canalsim {
namespace {

// Slack, in sample periods, for deciding that an observation reached a sample instant.
constexpr double instant_slack = 1e-9;

bool within(double value, double low, double high) {
  return std::isfinite(value) && value >= low && value <= high;
}

}  // namespace

const char* to_string(SensorKind kind) {
  switch (kind) {
    case SensorKind::level: return "level";
    case SensorKind::gate_position: return "gate_position";
    case SensorKind::flow: return "flow";
  }
  return "unknown";
}

SensorOptions SensorOptions::defaults_for(SensorKind kind) {
  SensorOptions options;
  options.kind = kind;
  if (kind != SensorKind::level) options.resolution = 0.0;
  return options;
}

Status SensorOptions::validate() const {
  return Validator()
      .require(kind == SensorKind::level || kind == SensorKind::gate_position || kind == SensorKind::flow, "kind",
               "expected level, gate_position or flow")
      .require(within(sample_period, 0.0, 3600.0) && sample_period != 0.0, "sample_period", sample_period,
               "a value in (0, 3600] s")
      .require(within(resolution, 0.0, 100.0), "resolution", resolution, "a value in [0, 100]")
      .require(within(noise_std, 0.0, 100.0), "noise_std", noise_std, "a value in [0, 100]")
      .require(within(delay, -600.0, 600.0), "delay", delay, "a value in [-600, 600] s")
      .require(within(offset, -1000.0, 1000.0), "offset", offset, "a value in [-1000, 1000]")
      .require(std::isfinite(start_time), "start_time", start_time, "a finite value in s")
      .status();
}

double quantise(double value, double resolution) { return laws::quantise(value, resolution); }

Sensor::Sensor(const SensorOptions& options)
    : options_(options), rng_(options.seed), noise_(0.0, options.noise_std > 0.0 ? options.noise_std : 1.0) {
  if (const Status status = options.validate(); !status) {
    throw std::invalid_argument(std::string(to_string(options.kind)) + " sensor: " + status.message());
  }
}

double Sensor::sample_instant(std::size_t k) const {
  return options_.start_time + static_cast<double>(k) * options_.sample_period;
}

double Sensor::measure(double true_value) {
  double reading = true_value + options_.offset;
  if (options_.noise_std > 0.0) reading += noise_(rng_);
  return quantise(reading, options_.resolution);
}

void Sensor::emit(double true_value) {
  times_.push_back(sample_instant(times_.size()));
  values_.push_back(measure(true_value));
}

// Linear interpolation of the observed history at t, holding the first value before it.
double Sensor::interpolate_history(double t) const {
  if (t <= history_.front().first) return history_.front().second;
  if (t >= history_.back().first) return history_.back().second;
  const auto after = std::upper_bound(history_.begin(), history_.end(), t,
                                      [](double x, const auto& entry) { return x < entry.first; });
  const auto& [t1, y1] = *after;
  const auto& [t0, y0] = *(after - 1);
  return y0 + (y1 - y0) * (t - t0) / (t1 - t0);
}

void Sensor::observe(double t, double true_value) {
  if (!history_.empty()) {
    if (t < history_.back().first) {
      throw std::invalid_argument("sensor: observation times must not decrease");
    }
    if (t == history_.back().first) history_.pop_back();
  }
  history_.emplace_back(t, true_value);

  const double h = options_.sample_period;
  // A sample is emitted once its instant and the instant it reads (earlier with a delay, later
  // with a negative one) have both been observed.
  const double lead = std::max(0.0, -options_.delay);
  while (sample_instant(times_.size()) + lead <= t + instant_slack * h) {
    emit(interpolate_history(sample_instant(times_.size()) - options_.delay));
  }
  // Forget observations older than the one before the next delayed instant.
  const double next_needed = sample_instant(times_.size()) - options_.delay;
  while (history_.size() >= 2 && history_[1].first <= next_needed) history_.pop_front();
}

void Sensor::finish(std::size_t count) {
  if (history_.empty()) return;
  while (times_.size() < count) emit(interpolate_history(sample_instant(times_.size()) - options_.delay));
}

void Sensor::sample(const std::function<double(double)>& signal, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    emit(signal(sample_instant(times_.size()) - options_.delay));
  }
}

}  // namespace canalsim
