// The parameters calibration can fit: named, bounded, transformed edits of a scenario, each with
// its unit and the scenario key it edits (docs/calibration.md lists them). The catalog is built
// for a scenario, since what it can carry depends on it (pools, the downstream structure, a
// reservoir).
//
//   name                    unit      key                                        search
//   cd_free                 -         head_gate.discharge_coefficient             log
//   cd_submerged            -         head_gate.submerged_discharge_coefficient   log
//   zero_head_mm            mm        head_gate.zero_head_m                       linear
//   cd_opening_exponent     -         head_gate.cd_opening_exponent               linear
//   cd_opening_curvature    -         head_gate.cd_opening_curvature              linear
//   border_floor_ratio      -         head_gate.border_floor_ratio                linear
//   manning_n (.i)          s m^-1/3  pools[i].manning_n                          log
//   bed_slope (.i)          m/m       pools[i].bed_slope                          linear
//   downstream_opening_mm   mm        downstream.gate.opening_m                   linear
//   downstream_cd           -         downstream.gate.discharge_coefficient       log
//   tail_level_mm           mm        downstream.tail_level_m                     linear
//   weir_crest_mm           mm        downstream.weir_crest_m                     linear
//   offset_mm               mm        sensors.offset_mm (every level sensor)       linear
//   offset_y_up_mm ...      mm        sensors.offset_y_up_mm (one sensor)          linear
//   sensor_delay_s          s         sensors.delay_s                              linear
//   actuator_speed_mm_s     mm/s      head_gate.actuator_speed_m_s (eq. 16)        log
//   pump_gain               m³/s/Hz   upstream.pump_m3s_per_hz                     log
//   pid_kp, pid_ti_s        Hz/m, s   upstream.pid_kp, upstream.pid_ti_s           log
//   pump_lag_s              s         upstream.pump_lag_s                          linear
//
// Roughness and coefficients are searched in log: they act multiplicatively and must stay
// positive. With more than one pool, the per-pool entries are named manning_n.1, manning_n.2, ...
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

enum class Transform { linear, log };

struct Parameter {
  std::string name;
  std::string unit;
  std::string key;           // the scenario key it edits, as in docs/scenarios.md
  double key_scale = 1.0;    // key value = parameter value × key_scale (mm -> m: 1e-3)
  std::string description;
  double low = 0.0, high = 0.0;   // bounds in the parameter's unit
  Transform transform = Transform::linear;
  // Finite-difference step in the search coordinate (log: a relative step).
  double step = 0.01;
  // Acts on the sampled levels only (offsets, delay): no re-simulation needed.
  bool sensor_only = false;
  // The low bound is the law as published (a regularisation of 0), not a guess: an estimate
  // that rests there is an answer — the recordings show none — not a doubtful optimum.
  bool low_is_published = false;
  // Values [unit] a calibration tries before it starts, where the cost is not monotone from the
  // scenario's value (a pump's lag rings the reservoir's loop): it starts from the one of these
  // and the scenario's value that leaves the lowest cost. Empty: it starts at the scenario's.
  std::vector<double> scan;
  std::function<double(const scenarios::Scenario&)> get;
  std::function<void(scenarios::Scenario&, double)> set;

  double to_search(double value) const;    // value -> search coordinate
  double from_search(double z) const;      // search coordinate -> value
};

// Every parameter the scenario can carry.
std::vector<Parameter> parameter_catalog(const scenarios::Scenario& scenario);

// "a, b, ...": the names of a catalog, for messages.
std::string parameter_names(const std::vector<Parameter>& catalog);

// The set a laboratory does not know (docs/calibration.md): the head gate's free and submerged
// discharge coefficients, the roughness of every pool, the downstream structure's setting (gate
// opening, or weir crest), a downstream gate's zero-head regularisation (its law near zero head
// differs from simulator to simulator and from canal to canal; docs/calibration.md) and an offset
// for every level sensor the recordings hold — except y_up_mm when the recorded upstream level
// drives the replay — and, when a tenth of the samples put Swamee's head gate under the floor of
// its regime border (a gate wide open at a millimetre of head), that floor, border_floor_ratio.
// Geometry, bed slope, the actuator and the pump are measured or specified and stay as they are
// unless --params names them.
std::vector<std::string> default_parameters(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings,
                                            bool upstream_replayed);

// The specs a calibration fits, from those the user gave (CalibrateOptions::parameters, --params)
// and the default set: none given = the default set; every one "+NAME" or "+NAME:LOW:HIGH" = the
// default set and those added (a default named again takes the bounds given, in its place);
// otherwise the specs given. Throws InputError for a mix of the two forms.
std::vector<std::string> chosen_parameters(const std::vector<std::string>& given, std::vector<std::string> defaults);

// The catalog entries named, in order; a spec "NAME:LOW:HIGH" replaces the bounds. Throws
// InputError naming an unknown or repeated name (with the catalog's names), malformed bounds, and
// a start (the scenario's value) outside the bounds.
std::vector<Parameter> select_parameters(const scenarios::Scenario& scenario, const std::vector<std::string>& specs);

}  // namespace canalsim::calibration
