#include "gates/actuator.hpp"

#include "core/laws.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/format.hpp"

namespace canalsim::gates {
namespace {
constexpr double arrival_tolerance = 1e-12;  // m; far below any gate's resolution
}  // namespace

Status ActuatorOptions::validate() const {
  return Validator()
      .require(mode == ActuatorMode::ideal || mode == ActuatorMode::rate_limited, "mode",
               "expected ideal or rate_limited")
      .require(std::isfinite(speed) && speed > 0.0 && speed <= 10.0, "speed", speed, "a gate speed in (0, 10] m/s")
      .require(std::isfinite(max_opening) && max_opening > 0.0 && max_opening <= 100.0, "max_opening", max_opening,
               "a value in (0, 100] m")
      .require(std::isfinite(initial_position) && initial_position >= 0.0 && initial_position <= max_opening,
               "initial_position", initial_position, "a value in [0, max_opening = " + format_g(max_opening) + "] m")
      .status();
}

GateActuator::GateActuator(const ActuatorOptions& options) : options_(options) {
  if (const Status status = options.validate(); !status) {
    throw std::invalid_argument("gate actuator: " + status.message());
  }
  position_ = options.initial_position;
}

double GateActuator::clamp_to_range(double x) const {
  return std::clamp(x, 0.0, options_.max_opening);
}

void GateActuator::reset(double position) {
  position_ = clamp_to_range(position);
  last_velocity_ = 0.0;
}

double GateActuator::advance(double dt, double command) {
  if (!(dt >= 0.0)) throw std::invalid_argument("gate actuator: dt must be >= 0");
  const double target = clamp_to_range(command);
  const double before = position_;
  if (options_.mode == ActuatorMode::ideal) {
    position_ = target;
  } else {
    // Exact solution of eq. (16) over dt: move at speed v, stop on the command.
    position_ = laws::rate_limited_move(position_, target, options_.speed * dt);
    // Land exactly on the command: a remainder of round-off size would otherwise leave the gate a
    // few ulps short and moving at a tiny speed on the next step.
    if (std::abs(target - position_) <= arrival_tolerance) position_ = target;
  }
  last_velocity_ = dt > 0.0 ? (position_ - before) / dt : 0.0;
  return position_;
}

}  // namespace canalsim::gates
