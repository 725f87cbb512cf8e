#include "gates/reservoir.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalsim::gates {
namespace {

// "field: expected a value in RANGE, got VALUE" when value is outside [low, high] (or not
// finite); `open_low` excludes the lower bound.
std::string check(const char* field, double value, double low, double high, bool open_low,
                  const char* unit) {
  const bool ok = std::isfinite(value) && (open_low ? value > low : value >= low) && value <= high;
  if (ok) return "";
  std::ostringstream out;
  out << field << ": expected a value in " << (open_low ? "(" : "[") << low << ", " << high
      << "] " << unit << ", got " << value;
  return out.str();
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

std::string ReservoirOptions::validate() const {
  for (const std::string& problem :
       {check("plan_area", plan_area, 0.0, 1e6, true, "m^2"),
        check("initial_level", initial_level, 0.0, 100.0, false, "m"),
        check("setpoint", setpoint, 0.0, 100.0, false, "m"),
        check("flow_per_hz", flow_per_hz, 0.0, 100.0, true, "m^3/s/Hz"),
        check("max_frequency", max_frequency, 0.0, 1000.0, true, "Hz"),
        check("proportional_gain", proportional_gain, 0.0, 1e9, false, "Hz/m"),
        check("integral_time", integral_time, 0.0, 1e9, true, "s"),
        check("derivative_time", derivative_time, 0.0, 1e6, false, "s"),
        check("tracking_time", tracking_time, 0.0, 1e6, true, "s")}) {
    if (!problem.empty()) return problem;
  }
  if (!std::isfinite(min_frequency) || min_frequency < 0.0 || min_frequency >= max_frequency) {
    std::ostringstream out;
    out << "min_frequency: expected a value in [0, max_frequency = " << max_frequency
        << ") Hz, got " << min_frequency;
    return out.str();
  }
  if (anti_windup != AntiWindup::none && anti_windup != AntiWindup::conditional_integration &&
      anti_windup != AntiWindup::back_calculation) {
    return "anti_windup: expected none, conditional_integration or back_calculation";
  }
  return "";
}

Reservoir::Reservoir(const ReservoirOptions& options) : options_(options) {
  const std::string problem = options.validate();
  if (!problem.empty()) throw std::invalid_argument("reservoir: " + problem);
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

  // Exact balance for the flows held over the step.
  const double inflow_volume = pump_flow() * dt;
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
