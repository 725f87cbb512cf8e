// Scenario: a complete, validated description of a canal experiment (geometry, structures,
// boundary conditions, sensors, numerics and the experiments to run), as read from a TOML file
// (docs/scenarios.md documents every key with unit, range and default).
//
// Plain data only: building solver objects from it is scenarios/build.*; reading it from TOML is
// scenarios/scenario_toml.*. Units: SI (m, s, m^3/s) for the hydraulics; the paper's mm for gate
// commands and sensors, as in recordings.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace canalsim::scenarios {

enum class OfftakeKind {
  fixed,    // a fixed discharge, whatever the level
  orifice,  // a gravity outlet: Q = K (h - invert)^exponent, K sized to deliver discharge_m3s at design
};

// A lateral offtake: a discharge withdrawn from a pool in the cell containing x.
struct OfftakeSpec {
  double x_m = 0.0;             // position from the pool's upstream end
  double discharge_m3s = 0.0;   // withdrawn (fixed) or design (orifice) discharge, >= 0
  OfftakeKind kind = OfftakeKind::fixed;
  double invert_m = 0.0;        // orifice: invert height above the local bed
  // orifice: the power of the head, in [0.5, 3]: 0.5 an orifice, 1.5 a side weir with its crest
  // at the invert (solver/reach.hpp).
  double exponent = 0.5;
  // orifice: K [m^(3 - exponent)/s], Cd A sqrt(2 g) for an orifice; 0 until scenarios/design.hpp
  // sizes it so that the outlet delivers discharge_m3s at the pool's design (steady, target-depth)
  // level.
  double coefficient = 0.0;
};

// One pool (reach) of prismatic channel.
struct PoolSpec {
  std::string name = "pool";
  double length_m = 5.0;
  double bottom_width_m = 0.08;
  double side_slope = 0.0;          // horizontal per vertical (0 = rectangular)
  double wall_height_m = 0.25;      // depth of the section; gate openings must stay below it
  double bed_slope = 0.0;           // positive = bed falls downstream
  double bed_elevation_m = 0.0;     // bed elevation at the pool's upstream end
  double manning_n = 0.010;         // s m^-1/3
  int cells = 100;
  double initial_depth_m = 0.0;     // first guess of the steady state; 0 = from the boundaries
  double target_depth_m = 0.0;      // design depth at the downstream end (check); 0 = none
  std::vector<OfftakeSpec> offtakes;
  // Design (backwater) depth and discharge at each cell centre, filled by scenarios/design.hpp
  // when the pool has a target depth; the first guess of the steady state. Not TOML keys.
  std::vector<double> design_depth_m;
  std::vector<double> design_discharge_m3s;
};

enum class GateLaw { swamee, simple };
inline const char* to_string(GateLaw law) { return law == GateLaw::swamee ? "swamee" : "simple"; }  // as in TOML

// A sluice gate (Swamee 1992, or the paper's eq. 9/11 with a discharge coefficient).
struct GateSpec {
  double width_m = 0.08;
  double max_opening_m = 0.05;      // mechanical range [0, max]
  double opening_m = 0.0;           // initial (or fixed) opening
  GateLaw law = GateLaw::swamee;
  // Multiplier on the law's published coefficient: Swamee's, or Cd = 0.6 of the simple laws
  // (scenarios/design.cpp gate_geometry).
  double discharge_coefficient = 1.0;
  // The multiplier in submerged flow (gates/sluice_gate.hpp); unset = discharge_coefficient.
  std::optional<double> submerged_discharge_coefficient;
  double submerged_coefficient() const { return submerged_discharge_coefficient.value_or(discharge_coefficient); }
  double leakage_m = 0.0;           // extra effective opening (a gate that does not seal)
  // Head below which the submerged law turns linear in the head (gates/sluice_gate.hpp
  // SluiceGateOptions::zero_head); 0 = the law as published.
  double zero_head_m = 0.0;
  // A discharge coefficient varying smoothly with the opening (gates/sluice_gate.hpp
  // SluiceGateOptions::opening_exponent): the law times exp(β x + γ x²), x = ln(a / a_ref).
  // 0 and 0 = the law as published; a_ref 0 = half the gate's max_opening_m.
  double cd_opening_exponent = 0.0;   // β
  double cd_opening_curvature = 0.0;  // γ
  double cd_reference_opening_m = 0.0;
  double cd_reference_opening() const { return cd_reference_opening_m > 0.0 ? cd_reference_opening_m : 0.5 * max_opening_m; }
  // The floor κ of the flow law's regime border over the tailwater, max(y_lc, κ y3) (gates/
  // sluice_gate.hpp SluiceGateOptions::border_floor_ratio): where the gate runs wide open near
  // zero head, the head κ y3 − y3 at which its flow frees.
  double border_floor_ratio = 1.05;
  double actuator_speed_m_s = 0.0;  // 0 = ideal actuator; else constant speed (paper eq. 16)
  bool controlled = false;          // driven by the experiment's input signal
  // opening_m = "auto": opening_m is computed (scenarios/design.hpp) so that the gate passes the
  // design flow with the upstream pool at its target depth.
  bool auto_opening = false;
};

enum class UpstreamKind { level, reservoir, discharge, recorded };

// What feeds the first gate (or the first pool when there is no head gate).
struct UpstreamSpec {
  UpstreamKind kind = UpstreamKind::level;
  double level_m = 0.060;           // level: fixed level; reservoir: PID setpoint
  double discharge_m3s = 0.0;       // discharge: fixed inflow into the first pool
  // Reservoir with a pump under PID level control (the laboratory's upstream pool).
  double plan_area_m2 = 0.05;
  double pump_m3s_per_hz = 6.0e-5;  // pump flow per Hz of drive frequency (3 L/s at 50 Hz)
  double max_frequency_hz = 50.0;
  double pid_kp = 2000.0;           // Hz per m of level error
  double pid_ti_s = 5.0;            // integral time
  double pid_td_s = 0.0;            // derivative time
  double pump_lag_s = 0.0;          // first-order lag of the pump's flow behind its drive (0: none)
};

enum class DownstreamKind { gate, weir, level, closed, pump };

struct DownstreamSpec {
  DownstreamKind kind = DownstreamKind::gate;
  GateSpec gate;                    // gate: fixed opening onto the tail level
  double tail_level_m = 0.0;        // gate: level downstream of the end gate (0 = free outfall)
  double weir_crest_m = 0.0;        // weir: crest height above the local bed
  double weir_coefficient = 1.7;    // weir: Q = C w (h - crest)^1.5, C in m^0.5/s
  double weir_width_m = 0.0;        // weir: 0 = channel width
  double level_m = 0.05;            // level: fixed depth at the end
  double pump_discharge_m3s = 0.0;  // pump: discharge drawn out of the last pool
  double pump_stop_depth_m = 0.1;   // pump: below this depth the pump throttles linearly to 0
};

struct SensorSpec {
  double period_s = 0.13;           // sampling period of every sensor
  double resolution_mm = 0.05;      // quantisation step (paper eq. 17); 0 = none
  double noise_std_mm = 0.0;        // Gaussian noise on level sensors
  double delay_s = 0.0;             // pure delay of the level sensors (negative: they lead the command)
  double offset_mm = 0.0;           // constant offset of the level sensors
  // Offsets of single level sensors, added to offset_mm (each sensor has its own zero).
  double offset_y_up_mm = 0.0, offset_y_dw_mm = 0.0, offset_y_dwe_mm = 0.0;
  double downstream_sensor_x_m = -1.0;  // position of y_dwe in the last pool; <0 = last cell
  double below_gate_sensor_x_m = 0.1;   // position of y_dw from the head gate
  std::uint64_t seed = 1;
};

enum class InputKind { constant, prbs, step, ramp, file };

// The gate command u(t) of an experiment, about its operating opening.
struct InputSpec {
  InputKind kind = InputKind::prbs;
  int prbs_stages = 9;              // 2..20; 9 stages give 511 bits
  double prbs_clock_s = 0.5;
  std::uint64_t prbs_seed = 1;
  double amplitude_mm = 5.0;        // PRBS: ±amplitude; step/ramp: final change
  double start_s = 10.0;            // step/ramp start
  double ramp_duration_s = 10.0;
  std::string file;                 // file: a recording whose u_mm column is replayed
};

// A change of flows at time t_s during an experiment (e.g. the ASCE flow-change tests): an
// offtake's discharge (a fixed offtake's withdrawal; an orifice's coefficient scaled so that it
// would deliver the new discharge at its design level) and/or the head inflow.
struct EventSpec {
  double t_s = 0.0;
  int pool = 0;                     // 1-based pool of the offtake; 0 = no offtake change
  int offtake = 1;                  // 1-based offtake within the pool
  double offtake_m3s = -1.0;        // new offtake discharge; < 0 = unchanged
  double inflow_m3s = -1.0;         // new head inflow (upstream kind "discharge"); < 0 = unchanged
};

struct ExperimentSpec {
  std::string name;
  double operating_opening_mm = 25.0;  // operating point of the controlled gate (if any)
  double duration_s = 255.5;
  double settle_s = 0.0;            // simulated but not recorded before t = 0
  InputSpec input;
  std::optional<SensorSpec> sensors;   // overrides the scenario's sensors
  std::vector<EventSpec> events;       // in time order
};

struct NumericsSpec {
  double cfl = 0.8;
  int order = 2;                    // 1 or 2
  bool van_leer_limiter = true;     // else generalised minmod with θ = limiter_theta (docs/numerics.md)
  double limiter_theta = 1.0;       // 1 = minmod, 2 = monotonised central (not used by van Leer's)
  double dry_depth_m = 1e-6;
  double steady_tolerance_m = 1e-10;  // steady state (Newton) convergence on depths
};

struct Scenario {
  std::string name;
  std::string description;
  std::string source;               // file (or built-in name) it came from, for messages
  UpstreamSpec upstream;
  std::optional<GateSpec> head_gate;  // gate between the upstream supply and the first pool
  std::vector<PoolSpec> pools;
  std::vector<GateSpec> gates;      // gates[i] sits between pools[i] and pools[i+1]
  DownstreamSpec downstream;
  SensorSpec sensors;
  NumericsSpec numerics;
  std::vector<ExperimentSpec> experiments;
  // [calibration.std]: what a calibration of this scenario left open, written by `canalsim
  // calibrate` — calibration parameter name (cd_free, manning_n, offset_y_dwe_mm, ...) → one
  // standard deviation in its unit. The diagnosis reads it as DiagnoseOptions::calibrated_std.
  std::map<std::string, double> calibrated_std;
  // [calibration.std_alone]: the same with the other parameters held at their estimates.
  std::map<std::string, double> calibrated_std_alone;
  // [calibration] baseline_rms_mm: the primary-channel residual RMS the calibration left on its
  // baseline recordings [mm]; 0 = not calibrated (DiagnoseOptions::baseline_rms_mm).
  double calibrated_baseline_rms_mm = 0.0;
  // [calibration.baseline_rms]: the same residual RMS for each level channel [mm].
  std::map<std::string, double> calibrated_baseline_rms_by_channel;
  // [calibration.baseline_slow_rms]: that residual's part slower than 2 s [mm]
  // (DiagnoseOptions::baseline_slow_rms_by_channel).
  std::map<std::string, double> calibrated_baseline_slow_rms_by_channel;

  const ExperimentSpec* find_experiment(const std::string& name) const;
};

// The cells over all the scenario's pools (a run's work grows with them).
inline int total_cells(const Scenario& s) {
  int cells = 0;
  for (const PoolSpec& pool : s.pools) cells += pool.cells;
  return cells;
}

}  // namespace canalsim::scenarios
