#include "gates/reservoir.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/format.hpp"

namespace canalsim::gates {
namespace {

// Finite and in [low, high]; `open_low` excludes the lower bound.
bool in_range(double value, double low, double high, bool open_low) {
  return std::isfinite(value) && (open_low ? value > low : value >= low) && value <= high;
}

}  // namespace

const char* to_string(AntiWindup scheme) {
  switch (scheme) {
    case AntiWindup::none: return "none";
    case AntiWindup::conditional_integration: return "conditional_integration";
    case AntiWindup::back_calculation: return "back_calculation";
  }
  return "unknown";
}

Status ReservoirOptions::validate() const {
  return Validator()
      .require(in_range(plan_area, 0.0, 1e6, true), "plan_area", plan_area, "a value in (0, 1e+06] m^2")
      .require(in_range(initial_level, 0.0, 100.0, false), "initial_level", initial_level, "a value in [0, 100] m")
      .require(in_range(setpoint, 0.0, 100.0, false), "setpoint", setpoint, "a value in [0, 100] m")
      .require(in_range(flow_per_hz, 0.0, 100.0, true), "flow_per_hz", flow_per_hz, "a value in (0, 100] m^3/s/Hz")
      .require(in_range(max_frequency, 0.0, 1000.0, true), "max_frequency", max_frequency, "a value in (0, 1000] Hz")
      .require(in_range(proportional_gain, 0.0, 1e9, false), "proportional_gain", proportional_gain,
               "a value in [0, 1e+09] Hz/m")
      .require(in_range(integral_time, 0.0, 1e9, true), "integral_time", integral_time, "a value in (0, 1e+09] s")
      .require(in_range(derivative_time, 0.0, 1e6, false), "derivative_time", derivative_time,
               "a value in [0, 1e+06] s")
      .require(in_range(tracking_time, 0.0, 1e6, true), "tracking_time", tracking_time, "a value in (0, 1e+06] s")
      .require(in_range(pump_lag, 0.0, 1e4, false), "pump_lag", pump_lag, "a value in [0, 10000] s")
      .require(std::isfinite(min_frequency) && min_frequency >= 0.0 && min_frequency < max_frequency,
               "min_frequency", min_frequency, "a value in [0, max_frequency = " + format_g(max_frequency) + ") Hz")
      .require(anti_windup == AntiWindup::none || anti_windup == AntiWindup::conditional_integration ||
                   anti_windup == AntiWindup::back_calculation,
               "anti_windup", "expected none, conditional_integration or back_calculation")
      .status();
}

Reservoir::Reservoir(const ReservoirOptions& options) : options_(options) {
  if (const Status status = options.validate(); !status) throw std::invalid_argument("reservoir: " + status.message());
  volume_ = options.initial_level * options.plan_area;
  initial_volume_ = volume_;
  previous_level_ = options.initial_level;
}

void Reservoir::start_at_steady_state(double outflow) {
  const double f = std::clamp(outflow / options_.flow_per_hz, options_.min_frequency,
                              options_.max_frequency);
  const double error = options_.setpoint - level();
  integral_ = f - options_.proportional_gain * error;
  frequency_ = f;
  pump_flow_ = f * options_.flow_per_hz;
}

void Reservoir::update_integral(double dt, double error, double unsaturated) {
  const double increment = options_.proportional_gain / options_.integral_time * error * dt;
  switch (options_.anti_windup) {
    case AntiWindup::none:
      integral_ += increment;
      break;
    case AntiWindup::conditional_integration: {
      // Integrate unless saturated with the error pushing further into the same limit.
      const bool pushing_up = unsaturated > options_.max_frequency && error > 0.0;
      const bool pushing_down = unsaturated < options_.min_frequency && error < 0.0;
      if (!pushing_up && !pushing_down) integral_ += increment;
      break;
    }
    case AntiWindup::back_calculation:
      integral_ += increment + (frequency_ - unsaturated) / options_.tracking_time * dt;
      break;
  }
}

double Reservoir::advance_pump(double dt) {
  // The lag integrated exactly for the drive held over the step; without one the pump follows it.
  const double commanded = frequency_ * options_.flow_per_hz;
  if (options_.pump_lag == 0.0) {
    pump_flow_ = commanded;
    return commanded * dt;
  }
  const double decay = -std::expm1(-dt / options_.pump_lag);  // 1 − e^(−dt/τ), exact for small steps
  const double volume = commanded * dt + (pump_flow_ - commanded) * options_.pump_lag * decay;
  pump_flow_ += (commanded - pump_flow_) * decay;
  return volume;
}

double Reservoir::advance(double dt, double outflow) {
  if (!(dt > 0.0) || !std::isfinite(outflow)) {
    throw std::invalid_argument("reservoir: dt must be > 0 and the outflow finite");
  }
  const double y = level();
  const double error = options_.setpoint - y;
  const double rate = (y - previous_level_) / dt;
  const double unsaturated =
      options_.proportional_gain * (error - options_.derivative_time * rate) + integral_;
  frequency_ = std::clamp(unsaturated, options_.min_frequency, options_.max_frequency);
  saturated_ = frequency_ != unsaturated;
  update_integral(dt, error, unsaturated);

  // Exact balance for the outflow held over the step and the pump's flow as it moved.
  const double inflow_volume = advance_pump(dt);
  const double outflow_volume = outflow * dt;
  volume_ += inflow_volume - outflow_volume;
  total_inflow_ += inflow_volume;
  total_outflow_ += outflow_volume;
  previous_level_ = y;
  return level();
}

double Reservoir::volume_balance_error() const {
  return volume_ - initial_volume_ - (total_inflow_ - total_outflow_);
}

}  // namespace canalsim::gates
