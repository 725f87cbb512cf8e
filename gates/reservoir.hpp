// Upstream reservoir fed by a pump under PID level control, as in the laboratory canal of the
// paper (Section 2 and 4.1: "the control of the upstream pool water level y_up(t) by varying the
// pump frequency was closed ... a range of frequency variation from 0 to 50 Hz", y_up ~ 60 mm).
//
// Model (prismatic reservoir of plan area A, level y measured from the gate sill):
//
//   dV/dt = Q_pump - Q_out,      y = V / A,      tau dQ_pump/dt = k_q f - Q_pump,   f in [f_min, f_max]
//
// with the pump flow proportional to its frequency f (k_q = flow_per_hz) after a first-order lag
// tau (pump_lag; 0, the default, makes Q_pump = k_q f: the drive's ramp and the water column's
// inertia are then taken as instant), and the controller
//
//   f_unsat = Kp (e + I - Td dy/dt),  dI/dt = e / Ti,  e = y_set - y,  f = clamp(f_unsat, f_min, f_max)
//
// (standard form with integral time Ti and derivative time Td, as the scenario keys pid_kp,
// pid_ti_s, pid_td_s; derivative on the measurement, so a setpoint change does not kick the
// pump). Internally the integral is kept in Hz, I_Hz = Kp I. The integral
// is protected against windup while the pump saturates, either by conditional integration (I
// stops while saturated and the error would drive it further into saturation) or by
// back-calculation (dI_Hz/dt = Kp e / Ti + (f - f_unsat) / T_t; Astrom & Hagglund, Advanced PID
// Control, 2006, Sec. 3.5).
//
// advance(dt, Q_out) holds the pump frequency and the outflow constant over the step and
// integrates the lag and the volume exactly for them (explicit in the controller, exact in the
// balance): Q_pump(t + dt) = k_q f + (Q_pump(t) - k_q f) e^(-dt/tau) and
// V(t + dt) = V(t) + k_q f dt + (Q_pump(t) - k_q f) tau (1 - e^(-dt/tau)) - Q_out dt. Given the outflow the solver used through the gate,
// mass is therefore conserved to round-off; cumulative inflow and outflow volumes are kept for
// the balance check.
#pragma once

#include <string>

#include "core/status.hpp"

namespace canalsim::gates {

enum class AntiWindup {
  none,                     // plain integration (winds up; for comparison)
  conditional_integration,  // freeze I while saturated and the error pushes further out
  back_calculation,         // bleed I with the saturation excess over tracking_time
};

const char* to_string(AntiWindup scheme);

// Defaults describe an assumed laboratory set-up (the paper gives only the 0-50 Hz range and the
// 60 mm level): a 0.05 m^2 head tank, a pump of 3 L/s at 50 Hz (the 45 mm operating point passes
// about 1.8 L/s through the 80 mm gate), and gains that make the closed loop
// A y'' + k_q Kp y' + (k_q Kp / Ti) y = 0 critically damped at about 0.4 rad/s
// (k_q Kp / A = 0.84 = 2 zeta omega, omega^2 = 0.168).
struct ReservoirOptions {
  double plan_area = 0.05;                 // A [m^2], range (0, 1e6]
  double initial_level = 0.060;            // y(0) [m], range [0, 100]
  double setpoint = 0.060;                 // y_set [m], range [0, 100]
  double flow_per_hz = 6e-5;               // k_q [m^3/s per Hz], range (0, 100]
  double min_frequency = 0.0;              // f_min [Hz], range [0, max_frequency)
  double max_frequency = 50.0;             // f_max [Hz], range (min_frequency, 1000]
  double proportional_gain = 700.0;        // Kp [Hz/m], range [0, 1e9]
  double integral_time = 5.0;              // Ti [s], range (0, 1e9]; 1e9 ~ no integral action
  double derivative_time = 0.0;            // Td [s], range [0, 1e6]
  AntiWindup anti_windup = AntiWindup::back_calculation;
  double tracking_time = 1.0;              // T_t [s] for back-calculation, range (0, 1e6]
  double pump_lag = 0.0;                   // tau [s], range [0, 1e4]: the pump's flow behind its drive

  // Ok, or one line naming the field and its allowed range (core/status.hpp).
  [[nodiscard]] Status validate() const;
};

class Reservoir {
 public:
  Reservoir() : Reservoir(ReservoirOptions{}) {}
  // Throws std::invalid_argument with validate()'s message when the options are invalid.
  explicit Reservoir(const ReservoirOptions& options);

  // Presets the integral so that, with the level on the setpoint, the pump delivers `outflow`
  // [m^3/s] (clamped to the pump's range): the experiment starts at steady state.
  void start_at_steady_state(double outflow);

  // Advances dt seconds (dt > 0) with the outflow [m^3/s] through the gate held constant;
  // returns the new level [m].
  double advance(double dt, double outflow);

  // Places the stored volume [m³] without touching the controller or the cumulative totals
  // (the linearisation perturbs the level; volume_balance_error() then counts the change).
  void set_volume(double volume) { volume_ = volume; }
  double level() const { return volume_ / options_.plan_area; }
  double volume() const { return volume_; }
  double initial_volume() const { return initial_volume_; }
  double frequency() const { return frequency_; }       // pump frequency of the last step [Hz]
  double pump_flow() const { return pump_flow_; }      // the pump's flow at the end of the last step [m^3/s]
  double integral() const { return integral_; }         // integral term Kp I [Hz]
  bool saturated() const { return saturated_; }
  double total_inflow() const { return total_inflow_; }    // cumulative pump volume [m^3]
  double total_outflow() const { return total_outflow_; }  // cumulative gate volume [m^3]
  // V - V0 - (inflow - outflow): zero up to round-off.
  double volume_balance_error() const;
  const ReservoirOptions& options() const { return options_; }

 private:
  void update_integral(double dt, double error, double unsaturated);
  // Moves the pump's flow dt seconds towards what the drive commands; returns the volume pumped.
  double advance_pump(double dt);

  ReservoirOptions options_;
  double volume_ = 0.0;
  double initial_volume_ = 0.0;
  double integral_ = 0.0;
  double frequency_ = 0.0;
  double pump_flow_ = 0.0;
  double previous_level_ = 0.0;
  bool saturated_ = false;
  double total_inflow_ = 0.0;
  double total_outflow_ = 0.0;
};

}  // namespace canalsim::gates
