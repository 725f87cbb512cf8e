#include "diagnosis/catalog.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/recording.hpp"

namespace canalsim::diagnosis {
namespace {

constexpr double kMm = 1e-3;
constexpr double kNone = 0.0;

using scenarios::Scenario;
using calibration::SensorModel;

// What each row changes: the scenario (hydraulics), the command the gate saw, or the readings.
void gate_speed(double speed_mm_s, Scenario& s, double) {
  s.head_gate->actuator_speed_m_s = std::isfinite(speed_mm_s) ? speed_mm_s * kMm : 0.0;
}
void leakage(double mm, Scenario& s, double) { s.head_gate->leakage_m += mm * kMm; }
void discharge(double factor, Scenario& s, double) {
  s.head_gate->discharge_coefficient *= factor;
  if (s.head_gate->submerged_discharge_coefficient) *s.head_gate->submerged_discharge_coefficient *= factor;
}
void roughness(double factor, Scenario& s, double) {
  for (auto& pool : s.pools) pool.manning_n *= factor;
}
void outflow(double share, Scenario& s, double inflow_m3s) {
  auto& pool = s.pools.front();
  pool.offtakes.push_back({0.5 * pool.length_m, share * inflow_m3s});
}
void downstream_setting(double mm, Scenario& s, double) {
  auto& gate = s.downstream.gate;
  gate.opening_m = std::clamp(gate.opening_m + mm * kMm, 0.0, gate.max_opening_m);
}

double command_reads_high(double mm, double logged, double) { return logged - mm; }
double command_gain(double gain, double logged, double) { return logged / gain; }
double command_drifts(double mm_per_min, double logged, double t_s) { return logged - mm_per_min * t_s / 60.0; }

void level_offset(double mm, SensorModel& m, const std::string& c) { m.channel_fault[c].offset_mm += mm; }
void level_delay(double s, SensorModel& m, const std::string& c) { m.channel_fault[c].delay_s += s; }
void level_drift(double mm_per_min, SensorModel& m, const std::string& c) { m.channel_fault[c].drift_mm_per_min += mm_per_min; }
void level_gain(double gain, SensorModel& m, const std::string& c) { m.channel_fault[c].gain *= gain; }
void level_lattice(double mm, SensorModel& m, const std::string& c) { m.channel_fault[c].resolution_mm = mm; }
void shared_datum(double mm, SensorModel& m, const std::string&) { m.offset_mm += mm; }
void clock_offset(double s, SensorModel& m, const std::string&) { m.clock_delay_s += s; }

const char* needs_head_gate(const Scenario& s) { return s.head_gate ? nullptr : "the scenario has no head gate"; }
const char* needs_pools(const Scenario& s) { return s.pools.empty() ? "the scenario has no pools" : nullptr; }
const char* needs_downstream_gate(const Scenario& s) {
  return s.downstream.kind == scenarios::DownstreamKind::gate ? nullptr : "the scenario's downstream end is not a gate";
}
const char* needs_controlled_gate(const Scenario& s) {
  return calibration::controlled_gate(s) ? nullptr : "the scenario has no controlled gate";
}

}  // namespace

const std::vector<EffectKind>& catalog() {
  using enum Acts;
  using enum Scope;
  using enum Search;
  using enum Coordinate;
  // θ ranges cover the plausible physics with margin; the probes are typical small magnitudes;
  // the draws are the blind test's magnitudes (blindtest.hpp).
  static const std::vector<EffectKind> rows = {
      // name, label, parameter, unit, acts, scope, search, coordinate, θ low, θ high, θ none, probe, material,
      // draw, overlap, spanned by, twin without gate position, edits, unsupported, description
      {"gate_rate_limit", "rate", "speed", "mm/s", hydraulics, canal, rate_limit, inverse, 0.0, 1.0, kNone, 0.05, 1.0 / 40.0,
       {0.05, 0.5, false}, Overlap::none, nullptr, nullptr, gate_speed, nullptr, nullptr, needs_head_gate,
       "the gate moves at a finite speed towards its command (paper eq. 16)"},
      {"gate_leakage", "leak", "extra_opening", "mm", hydraulics, canal, secant, identity, 0.0, 8.0, kNone, 1.0, 0.25,
       {0.5, 3.0, false}, Overlap::discharge_times_opening, "discharge_coefficient", "command_offset", leakage, nullptr,
       nullptr, needs_head_gate, "the head gate passes water as if it were opened further"},
      {"discharge_coefficient", "Cd", "multiplier", "-", hydraulics, canal, secant, identity, 0.5, 1.6, 1.0, 0.1, 0.04,
       {0.08, 0.2, true}, Overlap::discharge, nullptr, nullptr, discharge, nullptr, nullptr, needs_head_gate,
       "the head gate's discharge law is off by a constant factor"},
      {"friction", "fric", "manning_multiplier", "-", hydraulics, canal, secant, logarithm, std::log(0.2), std::log(8.0), 0.0,
       std::log(2.0), 0.3, {std::log(2.0), std::log(4.0), true}, Overlap::manning, nullptr, nullptr, roughness, nullptr,
       nullptr, needs_pools, "bed and wall roughness differs from the scenario's Manning n"},
      {"lateral_outflow", "lateral", "fraction_of_inflow", "-", hydraulics, canal, secant, identity, 0.0, 0.4, kNone, 0.08, 0.015,
       {0.03, 0.15, false}, Overlap::discharge, nullptr, nullptr, outflow, nullptr, nullptr, needs_pools,
       "water leaves the main pool through an unmodelled offtake or seepage"},
      {"downstream_gate", "dgate", "opening_change", "mm", hydraulics, canal, secant, identity, -10.0, 10.0, kNone, 1.0, 0.25,
       {0.5, 2.0, true}, Overlap::downstream_opening, nullptr, nullptr, downstream_setting, nullptr, nullptr,
       needs_downstream_gate, "the downstream gate is set higher or lower than the scenario says"},
      {"command_offset", "u-off", "offset", "mm", command, canal, secant, identity, -8.0, 8.0, kNone, 1.0, 0.25,
       {0.5, 3.0, true}, Overlap::discharge_times_opening, "discharge_coefficient", "gate_leakage", nullptr,
       command_reads_high, nullptr, needs_controlled_gate,
       "the logged command reads a constant amount above the gate's opening (the gate's zero is off)"},
      {"command_scale", "u-gain", "gain", "-", command, canal, secant, identity, 0.7, 1.4, 1.0, 0.1, 0.03, {0.05, 0.15, true},
       Overlap::discharge, nullptr, nullptr, nullptr, command_gain, nullptr, needs_controlled_gate,
       "the logged command is the gate's opening times a gain (the position sensor's span is off)"},
      {"command_drift", "u-drift", "rate", "mm/min", command, canal, secant, identity, -3.0, 3.0, kNone, 0.5, 0.1,
       {0.3, 1.0, true}, Overlap::none, nullptr, nullptr, nullptr, command_drifts, nullptr, needs_controlled_gate,
       "the logged command drifts away from the gate's opening during the recording"},
      {"command_delay", "clock", "delay", "s", readings, canal, delay_grid, identity, -2.0, 4.0, kNone, 0.5, 0.15,
       {0.3, 2.0, true}, Overlap::clock, nullptr, nullptr, nullptr, nullptr, clock_offset, nullptr,
       "every reading lags the logged command (negative: leads it): the gate acts late, or two loggers' clocks differ"},
      {"level_datum", "datum", "offset", "mm", readings, every_level_channel, median_offset, identity, -20.0, 20.0, kNone, 1.0,
       0.25, {0.5, 3.0, true}, Overlap::level_offset, nullptr, nullptr, nullptr, nullptr, shared_datum, nullptr,
       "every level sensor reads the same amount high or low: the datum they share is off"},
      {"sensor_offset", "offset", "offset", "mm", readings, each_level_channel, median_offset, identity, -20.0, 20.0, kNone, 1.0,
       0.25, {0.5, 3.0, true}, Overlap::level_offset, nullptr, nullptr, nullptr, nullptr, level_offset, nullptr,
       "one level sensor reads a constant amount high or low"},
      {"sensor_delay", "delay", "delay", "s", readings, each_level_channel, delay_grid, identity, -2.0, 4.0, kNone, 0.5, 0.15,
       {0.3, 2.0, true}, Overlap::none, nullptr, nullptr, nullptr, nullptr, level_delay, nullptr,
       "one level sensor lags (negative: leads) the others and the command"},
      {"sensor_drift", "drift", "rate", "mm/min", readings, each_level_channel, linear, identity, -5.0, 5.0, kNone, 0.5, 0.06,
       {0.15, 1.0, true}, Overlap::none, nullptr, nullptr, nullptr, nullptr, level_drift, nullptr,
       "one level sensor's zero drifts during the recording"},
      {"sensor_scale", "gain", "gain", "-", readings, each_level_channel, linear, identity, 0.7, 1.4, 1.0, 0.05, 0.01,
       {0.02, 0.06, true}, Overlap::none, nullptr, nullptr, nullptr, nullptr, level_gain, nullptr,
       "one level sensor reads the depth times a gain (its span is off)"},
      {"sensor_quantization", "quant", "resolution", "mm", readings, each_level_channel, lattice, identity, 0.0, 3.0, kNone, 0.2,
       0.1, {0.2, 1.0, false}, Overlap::none, nullptr, nullptr, nullptr, nullptr, level_lattice, nullptr,
       "one level sensor reports on a coarser lattice than the scenario says (paper eq. 17)"},
  };
  return rows;
}

std::string Effect::name() const {
  return channel.empty() ? std::string(kind->name) : std::string(kind->name) + "[" + channel + "]";
}

const EffectKind* kind_named(const std::string& name) {
  for (const auto& k : catalog()) {
    if (name == k.name) return &k;
  }
  return nullptr;
}

std::string catalog_names() {
  std::string names;
  for (const auto& k : catalog()) {
    names += (names.empty() ? "" : ", ") + std::string(k.name) + (k.scope == Scope::each_level_channel ? "[CHANNEL]" : "");
  }
  return names;
}

std::optional<Effect> effect_from_name(const std::string& name) {
  const auto open = name.find('[');
  const bool has_channel = open != std::string::npos;
  if (has_channel && (name.size() < open + 3 || name.back() != ']')) return std::nullopt;
  const EffectKind* kind = kind_named(name.substr(0, open));
  if (!kind) return std::nullopt;
  const std::string channel = has_channel ? name.substr(open + 1, name.size() - open - 2) : "";
  if (has_channel != (kind->scope == Scope::each_level_channel)) return std::nullopt;
  if (has_channel && !calibration::is_level(channel)) return std::nullopt;
  return Effect{kind, channel};
}

std::vector<Effect> effects_for(const std::vector<std::string>& level_channels) {
  std::vector<Effect> out;
  for (const auto& k : catalog()) {
    if (k.scope == Scope::each_level_channel) {
      for (const auto& c : level_channels) out.push_back({&k, c});
    } else if (k.scope == Scope::canal || level_channels.size() >= 2) {
      out.push_back({&k, ""});
    }
  }
  return out;
}

double to_parameter(const Effect& effect, double theta) {
  switch (effect.kind->coordinate) {
    case Coordinate::inverse: return theta <= 0.0 ? std::numeric_limits<double>::infinity() : 1.0 / theta;
    case Coordinate::logarithm: return std::exp(theta);
    case Coordinate::identity: return theta;
  }
  return theta;
}

double to_theta(const Effect& effect, double parameter) {
  switch (effect.kind->coordinate) {
    case Coordinate::inverse: return std::isinf(parameter) || parameter <= 0.0 ? 0.0 : 1.0 / parameter;
    case Coordinate::logarithm: return std::log(parameter);
    case Coordinate::identity: return parameter;
  }
  return parameter;
}

double parameter_per_theta(const Effect& effect, double theta) {
  switch (effect.kind->coordinate) {
    case Coordinate::inverse: return theta > 0.0 ? 1.0 / (theta * theta) : 0.0;  // |d(1/θ)/dθ|
    case Coordinate::logarithm: return std::exp(theta);
    case Coordinate::identity: return 1.0;
  }
  return 1.0;
}

double no_effect_parameter(const Effect& effect) { return to_parameter(effect, effect.kind->theta_none); }

bool is_material(const Effect& effect, double parameter) {
  return std::abs(to_theta(effect, parameter) - effect.kind->theta_none) >= effect.kind->material;
}

std::string unsupported_reason(const Effect& effect, const scenarios::Scenario& s) {
  const char* why = effect.kind->unsupported ? effect.kind->unsupported(s) : nullptr;
  return why ? why : "";
}

void apply_effect(const Effect& effect, double p, scenarios::Scenario& s, double inflow_m3s) {
  if (!effect.kind->edit_scenario) throw std::invalid_argument(effect.name() + " does not act on the hydraulics");
  if (const std::string why = unsupported_reason(effect, s); !why.empty()) {
    throw std::invalid_argument(effect.name() + ": " + why);
  }
  effect.kind->edit_scenario(p, s, inflow_m3s);
}

void apply_effect(const Effect& effect, double p, SensorModel& m) {
  if (!effect.kind->edit_sensors) throw std::invalid_argument(effect.name() + " is not an instrument effect");
  effect.kind->edit_sensors(p, m, effect.channel);
}

void apply_effect(const Effect& effect, double p, calibration::Replay& replay) {
  if (!effect.kind->gate_saw) throw std::invalid_argument(effect.name() + " does not act on the command");
  const auto gate_saw = [&](double logged, double t) { return std::max(effect.kind->gate_saw(p, logged, t), 0.0); };
  const std::vector<double>& t = replay.drive.column(columns::time);
  std::vector<double> u = replay.drive.column(columns::gate_command);
  for (std::size_t k = 0; k < u.size(); ++k) u[k] = gate_saw(u[k], std::max(t[k], 0.0));
  replay.drive.set_column(columns::gate_command, std::move(u));
  replay.operating_point_mm = gate_saw(replay.operating_point_mm, 0.0);
  if (!replay.drive.meta("operating_opening_mm").empty()) {
    replay.drive.set_meta("operating_opening_mm", std::to_string(replay.operating_point_mm));
  }
}

std::string separating_experiment(const std::string& a_name, const std::string& b_name) {
  // Per-channel effects are compared by their kind; the channel is named in the sentence.
  const auto kind_of = [](const std::string& n) { return n.substr(0, n.find('[')); };
  const std::string a = kind_of(a_name), b = kind_of(b_name);
  const auto pair_is = [&](const char* x, const char* y) { return (a == x && b == y) || (a == y && b == x); };
  const auto one_of = [&](const char* x) { return a == x || b == x; };
  if (a == b) {
    return "a second sensor beside each of the two, or the two read in still water: the faulty one disagrees with its "
           "neighbour";
  }
  if (pair_is("gate_leakage", "command_offset")) {
    return "the gate position logged beside its command, or the gate closed with the flow measured: a command that "
           "reads high and a gate that leaks change the hydraulics identically";
  }
  if (pair_is("gate_leakage", "discharge_coefficient") || pair_is("command_offset", "discharge_coefficient") ||
      pair_is("command_scale", "discharge_coefficient")) {
    return "steps at a small and a large gate opening: a leak adds the same extra opening at both (it dominates "
           "when the gate is nearly closed), a discharge coefficient scales the flow in proportion to the opening";
  }
  if ((one_of("sensor_offset") || one_of("level_datum")) && one_of("downstream_gate")) {
    return "a recording at another flow, or the levels read in still water with the gates closed: an offset "
           "shifts every reading by the same amount at any flow, a downstream gate setting shifts the levels by "
           "an amount that grows with the flow";
  }
  if (one_of("sensor_offset") && one_of("sensor_scale")) {
    return "a recording at a clearly different level: an offset is the same at every depth, a scale error grows "
           "with the depth";
  }
  if (one_of("friction") && (one_of("downstream_gate") || one_of("sensor_offset") || one_of("level_datum"))) {
    return "recordings at two flows: friction changes the level drop along the pool with the square of the flow, "
           "an offset or a downstream setting shifts the levels more uniformly";
  }
  if (one_of("lateral_outflow") && (one_of("discharge_coefficient") || one_of("gate_leakage"))) {
    return "a level sensor upstream of the offtake, or a flow measured at the downstream gate: an outflow along "
           "the pool lowers the downstream flow, a head-gate law changes the inflow itself";
  }
  if ((one_of("sensor_delay") || one_of("command_delay")) && one_of("gate_rate_limit")) {
    return "a step of the command with the gate position logged: a slow gate lags the command in its position, "
           "a sensor delay lags only the readings";
  }
  if (one_of("sensor_drift") || one_of("command_drift")) {
    return "a longer recording, or one started again after a pause: a drift keeps growing with time, the other "
           "effect does not";
  }
  return "an experiment at another operating point (gate opening and flow), where the two effects change the "
         "levels by different amounts";
}

}  // namespace canalsim::diagnosis
