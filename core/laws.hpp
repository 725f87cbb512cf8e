// The laws of Gharab, Feliu-Batlle & Rivas-Perez (2019) that more than one module applies, each
// written once. Units are whatever the caller uses consistently (metres in the simulator,
// millimetres in recordings and reduced models): every law here is homogeneous of degree one.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace canalsim::laws {

// Eq. (17): a sensor of resolution r reads r·nint(y / r). nint rounds half away from zero
// (std::round) everywhere in canalsim: the simulated sensors, the reduced models' quantised
// output and the diagnosis' expected readings agree to the last bit. r <= 0 is an ideal sensor.
inline double quantise(double value, double resolution) {
  return resolution > 0.0 ? resolution * std::round(value / resolution) : value;
}

// Eq. (16): a gate actuator of constant speed v moves towards its command and stops on it. One
// interval of length dt moves the position by at most v·dt (`max_travel`); an infinite travel is
// the ideal actuator, at the command at once.
inline double rate_limited_move(double position, double command, double max_travel) {
  if (!std::isfinite(max_travel)) return command;
  return position + std::clamp(command - position, -max_travel, max_travel);
}

// Eqs. (8), (10), (23): the upstream level at the border between free and submerged flow under a
// gate of opening a with tailwater level y_dwe, y_lc = 0.81 y_dwe (y_dwe / a)^0.72. Free flow when
// the upstream level is above it. +∞ for a closed gate (a <= 0); 0 for a dry tail (y_dwe <= 0).
inline constexpr double regime_border_coefficient = 0.81;
inline constexpr double regime_border_exponent = 0.72;
inline double free_flow_limit_level(double y_dwe, double opening) {
  if (opening <= 0.0) return std::numeric_limits<double>::infinity();
  if (y_dwe <= 0.0) return 0.0;
  return regime_border_coefficient * y_dwe * std::pow(y_dwe / opening, regime_border_exponent);
}

}  // namespace canalsim::laws
