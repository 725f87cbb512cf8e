// The catalog of candidate physics: effects that a canal simulator (or a recording's instruments)
// commonly leave out, each a one-parameter extension of the scenario model. The catalog is a
// table of behaviours (catalog.cpp): each row says what its effect changes, how its parameter is
// searched and drawn, what a calibration of the scenario already leaves open of it and which
// channel it acts on. Adding an effect is adding a row; docs/diagnosis.md lists them.
//
// An effect acts on one of three things:
//   hydraulics  the canal itself (the head gate's law, friction, an outflow, the downstream
//               gate): the scenario is edited and every recording re-simulated;
//   command     the logged command differs from what the gate did (offset, scale, drift): the
//               replay's drive is edited and re-simulated;
//   readings    an instrument (offset, delay, drift, scale, quantisation of one level sensor; the
//               clock between the command and every reading; a datum shared by every level
//               sensor): one nominal simulation is re-observed, no re-simulation.
// Instrument faults act on one channel each: a row of scope `each_level_channel` stands for one
// effect per level channel the recordings carry, named `sensor_offset[y_dwe_mm]`.
//
// Each parameter is searched in an internal coordinate θ in which the response is closer to
// linear: the inverse speed 1/v for the rate limit (θ = 0 is the ideal actuator), log n for
// friction, the parameter itself otherwise.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "calibration/observe.hpp"
#include "calibration/replay.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::diagnosis {

enum class Acts { hydraulics, command, readings };
enum class Scope {
  canal,                // the canal or the whole command
  each_level_channel,   // one effect per level channel (sensor_offset[y_up_mm], ...)
  every_level_channel,  // one effect on every level channel at once: a common cause
};
// How the scenario engine searches the parameter (scenario_fits.cpp).
enum class Search {
  secant,         // Gauss–Newton with a secant Jacobian, re-simulating
  rate_limit,     // from the logged gate position, else a scan of speeds
  median_offset,  // the median residual of the channels it acts on
  delay_grid,     // a grid of delays of both signs, refined by a parabola
  lattice,        // the largest lattice that holds the recorded levels
  linear,         // least squares on the signature (the prediction is linear in the parameter)
};
enum class Coordinate { identity, inverse, logarithm };
// What a calibration of the scenario may already have fitted of the effect (calibrated.hpp).
enum class Overlap { none, discharge, discharge_times_opening, manning, downstream_opening, level_offset, clock };

// A blind test's draw (blindtest.hpp): |θ − θ_none| uniform in [low, high], of either sign when
// either_sign, else above θ_none.
struct BlindDraw {
  double low = 0.0, high = 0.0;
  bool either_sign = false;
};

struct EffectKind {
  const char* name;        // as in the JSON verdict (with "[channel]" for each_level_channel)
  const char* label;       // a short name for tables
  const char* parameter;   // parameter name in the JSON
  const char* unit;
  Acts acts;
  Scope scope;
  Search search;
  Coordinate coordinate;
  double theta_low, theta_high;  // search range in the internal coordinate
  double theta_none;       // θ of "no effect"
  double theta_probe;      // first trial step (secant) or signature step (linear)
  // Smallest departure |θ − θ_none| worth naming: half the smallest magnitude a laboratory
  // would care about; smaller fits are model tolerance.
  double material;
  BlindDraw draw;
  Overlap overlap;
  // The effect whose parameter, refitted jointly with this one, takes up what the calibration
  // leaves open of it (calibrated.hpp calibration_spanned_by), or null.
  const char* spanned_by;
  // An effect these recordings cannot tell from this one when they hold no gate position: the
  // two change the hydraulics identically (a command that reads high is a gate that leaks).
  const char* twin_without_gate_position;
  // Hydraulics: edits the scenario (`inflow_m3s` is the reference of a share of the inflow).
  void (*edit_scenario)(double parameter, scenarios::Scenario& scenario, double inflow_m3s);
  // Command: the opening the gate had when the logger wrote `logged_mm` at `t_s`.
  double (*gate_saw)(double parameter, double logged_mm, double t_s);
  // Readings: edits the sensor model (channel "" for a row of another scope).
  void (*edit_sensors)(double parameter, calibration::SensorModel& sensors, const std::string& channel);
  // Why a scenario cannot carry the effect (no head gate...), or null for "it can".
  const char* (*unsupported)(const scenarios::Scenario& scenario);
  const char* description;
};

// One effect: a row of the catalog, on a channel for the per-channel rows.
struct Effect {
  const EffectKind* kind = nullptr;
  std::string channel;     // level channel of an each_level_channel row, else ""
  std::string name() const;
  bool operator==(const Effect& other) const { return kind == other.kind && channel == other.channel; }
};

const std::vector<EffectKind>& catalog();
// The kind of that name (without a channel), or null.
const EffectKind* kind_named(const std::string& name);
// "sensor_offset[y_dwe_mm]", "gate_leakage": the effect, or nullopt for an unknown kind, a
// channel on a row without one, a per-channel row without one, or a channel that is not a level.
std::optional<Effect> effect_from_name(const std::string& name);
// "a, b, ..., z": the catalog's kind names (per-channel ones as kind[CHANNEL]), for messages
// that reject an unknown one.
std::string catalog_names();
// Every effect of the catalog on recordings whose level channels are `level_channels`: a
// per-channel row once per channel, a common-cause row when there are at least two.
std::vector<Effect> effects_for(const std::vector<std::string>& level_channels);

// Parameter value (user units) ↔ internal coordinate θ.
double to_parameter(const Effect& effect, double theta);
double to_theta(const Effect& effect, double parameter);
// |d parameter / d θ| at θ: maps a standard deviation in θ to the parameter's unit (0 for the rate
// limit at θ = 0, the ideal actuator).
double parameter_per_theta(const Effect& effect, double theta);
// The parameter of "no effect" (0 mm, multiplier 1, infinite speed for the rate limit).
double no_effect_parameter(const Effect& effect);
// |θ(parameter) − θ_none| ≥ the row's material departure.
bool is_material(const Effect& effect, double parameter);

// The level sensor model and its expected reading live with the replay machinery
// (calibration/observe.hpp); reading effects edit a SensorModel.
using calibration::SensorModel;
using calibration::expected_reading;
using calibration::sensor_model_of;

// Applies a hydraulic effect to a scenario (`inflow_m3s`: the reference of lateral_outflow).
// Throws std::invalid_argument for an effect that does not act on the hydraulics, or that the
// scenario cannot express (no head gate, no downstream gate), naming the missing part.
void apply_effect(const Effect& effect, double parameter, scenarios::Scenario& scenario, double inflow_m3s);
// Applies a reading effect to a sensor model; std::invalid_argument for another kind.
void apply_effect(const Effect& effect, double parameter, SensorModel& sensors);
// Applies a command effect to a replay: its drive's command and its operating point become what
// the gate did; std::invalid_argument for another kind.
void apply_effect(const Effect& effect, double parameter, calibration::Replay& replay);

// The experiment that would tell two effects apart when a set of recordings cannot (an ambiguous
// pair of the diagnosis, pipeline.hpp): what differs between their signatures, in words.
std::string separating_experiment(const std::string& a, const std::string& b);

// Why the scenario cannot carry the effect, or empty.
std::string unsupported_reason(const Effect& effect, const scenarios::Scenario& scenario);

}  // namespace canalsim::diagnosis
