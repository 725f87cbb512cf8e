// Gate actuator: the servo-positioning system that moves the gate towards the commanded opening.
//
// Paper eq. (16) (Gharab, Feliu-Batlle & Rivas-Perez 2019, Section 4.2): the gate moves at a
// constant speed v towards the command u(t) and stops when it gets there,
//
//   dx_up/dt = v sign(u(t) - x_up(t))   if x_up != u,   0 otherwise.
//
// Within a step of length dt with a constant command, the exact solution moves by
// min(v dt, |u - x|) towards u, so the gate never overshoots and stops exactly on the command.
// The ideal actuator follows the command instantly. Positions and commands are clamped to the
// mechanical range [0, max_opening].
#pragma once

#include <string>

#include "core/status.hpp"

namespace canalsim::gates {

enum class ActuatorMode {
  ideal,         // x_up = u at once
  rate_limited,  // eq. (16): constant speed towards the command
};

struct ActuatorOptions {
  ActuatorMode mode = ActuatorMode::rate_limited;
  // Gate speed v of eq. (16) [m/s]. The paper does not give it; 10 mm/s lets a 10 mm PRBS
  // reversal finish within 1 s, well inside the 0.5 s clock's two-bit runs. Range (0, 10].
  double speed = 0.010;
  // Mechanical range of the gate [m]: the laboratory gate opens 0-50 mm. Range (0, 100].
  double max_opening = 0.050;
  double initial_position = 0.0;  // [m], range [0, max_opening]

  // Ok, or one line naming the field and its allowed range (core/status.hpp).
  [[nodiscard]] Status validate() const;
};

class GateActuator {
 public:
  GateActuator() : GateActuator(ActuatorOptions{}) {}
  // Throws std::invalid_argument with validate()'s message when the options are invalid.
  explicit GateActuator(const ActuatorOptions& options);

  // Moves the gate for dt seconds (dt >= 0) under a constant command and returns the new
  // position [m]. The command is clamped to [0, max_opening].
  double advance(double dt, double command);

  double position() const { return position_; }
  // Velocity over the last advance() call [m/s] (0 before the first call or for dt = 0).
  double last_velocity() const { return last_velocity_; }
  // Places the gate (clamped), e.g. at the operating point before an experiment starts.
  void reset(double position);
  const ActuatorOptions& options() const { return options_; }

 private:
  double clamp_to_range(double x) const;

  ActuatorOptions options_;
  double position_ = 0.0;
  double last_velocity_ = 0.0;
};

}  // namespace canalsim::gates
