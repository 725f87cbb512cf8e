// The catalog of candidate physics: effects that a canal simulator (or a recording's instruments)
// commonly leave out, each a one-parameter extension of the scenario model.
//
//   effect                 parameter (unit)            what changes
//   gate_rate_limit        speed (mm/s)                head_gate.actuator_speed_m_s (paper eq. 16)
//   sensor_quantization    resolution (mm)             sensors.resolution_mm (paper eq. 17)
//   sensor_delay           delay (s; negative: lead)   sensors.delay_s, added
//   sensor_offset          offset (mm)                 sensors.offset_mm, added
//   gate_leakage           extra opening (mm)          head_gate.leakage_m, added
//   discharge_coefficient  multiplier (-)              head_gate.discharge_coefficient, times
//   friction               Manning n multiplier (-)    pools[*].manning_n, times
//   lateral_outflow        fraction of inflow (-)      an offtake at mid-length of the first pool
//   downstream_gate        opening change (mm)         downstream.gate.opening_m, added
//
// Sensor effects act on the sampled outputs only, so they are applied to one noise-free nominal
// simulation (SensorModel); the others change the hydraulics and are re-simulated.
//
// Each parameter is searched in an internal coordinate θ in which the response is closer to
// linear: the inverse speed 1/v for the rate limit (θ = 0 is the ideal actuator), log n for
// friction, the parameter itself otherwise.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "calibration/observe.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::diagnosis {

enum class Effect {
  gate_rate_limit,
  sensor_quantization,
  sensor_delay,
  sensor_offset,
  gate_leakage,
  discharge_coefficient,
  friction,
  lateral_outflow,
  downstream_gate,
};

struct EffectInfo {
  Effect effect;
  const char* name;        // as in the JSON verdict
  const char* parameter;   // parameter name in the JSON
  const char* unit;
  bool sensor_only;        // applied to sampled outputs, no re-simulation
  double theta_low, theta_high;  // search range in the internal coordinate
  double theta_none;       // θ of "no effect"
  double theta_probe;      // first trial step for the secant search
  // Smallest departure from "no effect" worth naming, in parameter units (|value - none|): half
  // the smallest magnitude a laboratory would care about; smaller fits are model tolerance.
  double material;
  const char* description;
};

const std::vector<EffectInfo>& catalog();
const EffectInfo& info(Effect effect);
std::optional<Effect> effect_from_name(const std::string& name);
// "a, b, ..., z": the catalog's effect names, for messages that reject an unknown one.
std::string catalog_names();

// Parameter value (user units) ↔ internal coordinate θ.
double to_parameter(Effect effect, double theta);
double to_theta(Effect effect, double parameter);
// |d parameter / d θ| at θ: maps a standard deviation in θ to the parameter's unit (0 for the rate
// limit at θ = 0, the ideal actuator).
double parameter_per_theta(Effect effect, double theta);
// The parameter of "no effect" (0 mm, multiplier 1, infinite speed for the rate limit).
double no_effect_parameter(Effect effect);
// |value - no effect| in the parameter's own unit, for the materiality check (for the rate limit:
// 1/v in s/mm against 1/material).
bool is_material(Effect effect, double parameter);

// The level sensor model and its expected reading live with the replay machinery
// (calibration/observe.hpp); sensor effects edit a SensorModel.
using calibration::SensorModel;
using calibration::expected_reading;
using calibration::sensor_model_of;

// Applies a hydraulic effect to a scenario. `inflow_m3s` is the recording's nominal inflow, the
// reference of lateral_outflow. Sensor effects change `sensors` instead. Throws
// std::invalid_argument for an effect the scenario cannot express (no head gate, no downstream
// gate) naming the missing part.
void apply_effect(Effect effect, double parameter, scenarios::Scenario& scenario, double inflow_m3s);
void apply_effect(Effect effect, double parameter, SensorModel& sensors);

// The experiment that would tell two effects apart when a set of recordings cannot (an ambiguous
// pair of the diagnosis, pipeline.hpp): what differs between their signatures, in words.
std::string separating_experiment(const std::string& a, const std::string& b);

// Why the scenario cannot carry the effect, or empty.
std::string unsupported_reason(Effect effect, const scenarios::Scenario& scenario);

}  // namespace canalsim::diagnosis
