// Sensors: what the laboratory's instruments make of a continuous signal.
//
// A sensor samples at the experiment's period h (0.13 s in the paper, Section 4.3) and reports
//
//   y_meas(k h) = Q_r( y(k h - d) + offset + n_k ),    n_k ~ N(0, sigma^2) i.i.d.,
//
// with a pure delay d (negative: the readings lead, as when the level logger's clock runs ahead
// of the command's — a time offset of either sign between the two), a constant offset, Gaussian noise (std::mt19937_64 seeded, so a run is
// reproducible), and the quantisation of the paper's eq. (17),
//
//   Q_r(y) = r nint(y / r),   r = 0.05 mm for the ultrasonic level sensors,
//
// applied last because it is the instrument's output resolution. nint rounds half away from
// zero (std::round).
//
// Two ways to feed a sensor: observe(t, y) with the true value at the simulator's own
// (non-decreasing) times, the sensor interpolating linearly to the delayed sample instants; or
// sample(f, count) with a function it can evaluate anywhere. Use one or the other per sensor.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "core/status.hpp"

namespace canalsim {

enum class SensorKind {
  level,          // water level [m]; ultrasonic, 0.05 mm resolution (paper Section 4.2)
  gate_position,  // gate opening [m]; the paper gives no resolution: none by default
  flow,           // discharge [m^3/s]; ideal by default
};

const char* to_string(SensorKind kind);

// All quantities in SI units of the measured signal (m, or m^3/s for flow).
struct SensorOptions {
  SensorKind kind = SensorKind::level;
  double sample_period = 0.13;  // h [s], range (0, 3600]
  double resolution = 0.05e-3;  // r of eq. (17), range [0, 100]; 0 = no quantisation
  double noise_std = 0.0;       // sigma, range [0, 100]
  double delay = 0.0;           // d [s], range [-600, 600]; negative: the readings lead
  double offset = 0.0;          // added bias, range [-1000, 1000]
  double start_time = 0.0;      // time of the first sample [s], finite
  std::uint64_t seed = 1;       // noise generator seed

  // Defaults of each kind: level as above; gate position and flow without quantisation.
  static SensorOptions defaults_for(SensorKind kind);
  // Ok, or one line naming the field and its allowed range (core/status.hpp).
  [[nodiscard]] Status validate() const;
};

// Paper eq. (17): r nint(value / r); the value itself when r = 0.
double quantise(double value, double resolution);

class Sensor {
 public:
  Sensor() : Sensor(SensorOptions{}) {}
  // Throws std::invalid_argument with validate()'s message when the options are invalid.
  explicit Sensor(const SensorOptions& options);

  // Feeds the true value at time t (t must not decrease; a repeated t replaces the value).
  // Emits every sample whose instant start + k h and whose read instant start + k h - d are at
  // or before t. Samples whose read instant precedes the first observation take the first
  // observed value (the experiment starts from a steady state). Throws std::invalid_argument
  // when t decreases.
  void observe(double t, double true_value);

  // Emits the samples still owed up to `count` in all: with a negative delay the last ones read
  // past the last observation, and take its value (the run ends there; the calibration's
  // replay clamps at the end the same way).
  void finish(std::size_t count);

  // Samples `count` instants start + k h of a function defined for all t, evaluating it at
  // start + k h - d directly.
  void sample(const std::function<double(double)>& signal, std::size_t count);

  // Offset, noise and quantisation of one reading (no delay): advances the noise generator.
  double measure(double true_value);

  const std::vector<double>& times() const { return times_; }
  const std::vector<double>& values() const { return values_; }
  const SensorOptions& options() const { return options_; }

 private:
  double sample_instant(std::size_t k) const;
  double interpolate_history(double t) const;
  void emit(double true_value);

  SensorOptions options_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
  std::deque<std::pair<double, double>> history_;  // (t, true value), oldest first
  std::vector<double> times_;
  std::vector<double> values_;
};

}  // namespace canalsim
