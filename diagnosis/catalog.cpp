#include "diagnosis/catalog.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace canalsim::diagnosis {
namespace {
constexpr double kMm = 1e-3;
}  // namespace

const std::vector<EffectInfo>& catalog() {
  // θ ranges cover the plausible physics with margin; the probes are typical small magnitudes.
  static const std::vector<EffectInfo> effects = {
      {Effect::gate_rate_limit, "gate_rate_limit", "speed", "mm/s", false, 0.0, 1.0, 0.0, 0.05, 40.0,
       "the gate moves at a finite speed towards its command (paper eq. 16)"},
      {Effect::sensor_quantization, "sensor_quantization", "resolution", "mm", true, 0.0, 3.0, 0.0, 0.2, 0.1,
       "level sensors report on a coarser lattice than the scenario says (paper eq. 17)"},
      {Effect::sensor_delay, "sensor_delay", "delay", "s", true, -2.0, 4.0, 0.0, 0.5, 0.15,
       "level readings lag the water, or lag or lead the command (loggers on two clocks)"},
      {Effect::sensor_offset, "sensor_offset", "offset", "mm", true, -20.0, 20.0, 0.0, 1.0, 0.25,
       "level sensors read a constant amount high or low"},
      {Effect::gate_leakage, "gate_leakage", "extra_opening", "mm", false, 0.0, 8.0, 0.0, 1.0, 0.25,
       "the head gate passes water as if it were opened further"},
      {Effect::discharge_coefficient, "discharge_coefficient", "multiplier", "-", false, 0.5, 1.6, 1.0, 1.1, 0.04,
       "the head gate's discharge law is off by a constant factor"},
      {Effect::friction, "friction", "manning_multiplier", "-", false, std::log(0.2), std::log(8.0), 0.0,
       std::log(2.0), 0.3, "bed and wall roughness differs from the scenario's Manning n"},
      {Effect::lateral_outflow, "lateral_outflow", "fraction_of_inflow", "-", false, 0.0, 0.4, 0.0, 0.08, 0.015,
       "water leaves the main pool through an unmodelled offtake or seepage"},
      {Effect::downstream_gate, "downstream_gate", "opening_change", "mm", false, -10.0, 10.0, 0.0, 1.0, 0.25,
       "the downstream gate is set higher or lower than the scenario says"},
  };
  return effects;
}

const EffectInfo& info(Effect effect) {
  for (const auto& e : catalog()) {
    if (e.effect == effect) return e;
  }
  throw std::logic_error("diagnosis: effect missing from the catalog");
}

std::string catalog_names() {
  std::string names;
  for (const auto& e : catalog()) names += (names.empty() ? "" : ", ") + std::string(e.name);
  return names;
}

std::optional<Effect> effect_from_name(const std::string& name) {
  for (const auto& e : catalog()) {
    if (name == e.name) return e.effect;
  }
  return std::nullopt;
}

double to_parameter(Effect effect, double theta) {
  switch (effect) {
    case Effect::gate_rate_limit:
      return theta <= 0.0 ? std::numeric_limits<double>::infinity() : 1.0 / theta;
    case Effect::friction: return std::exp(theta);
    default: return theta;
  }
}

double to_theta(Effect effect, double parameter) {
  switch (effect) {
    case Effect::gate_rate_limit: return std::isinf(parameter) || parameter <= 0.0 ? 0.0 : 1.0 / parameter;
    case Effect::friction: return std::log(parameter);
    default: return parameter;
  }
}

double parameter_per_theta(Effect effect, double theta) {
  switch (effect) {
    case Effect::gate_rate_limit: return theta > 0.0 ? 1.0 / (theta * theta) : 0.0;  // |d(1/θ)/dθ|
    case Effect::friction: return std::exp(theta);
    default: return 1.0;
  }
}

double no_effect_parameter(Effect effect) { return to_parameter(effect, info(effect).theta_none); }

bool is_material(Effect effect, double parameter) {
  const EffectInfo& e = info(effect);
  switch (effect) {
    case Effect::gate_rate_limit: return std::isfinite(parameter) && parameter <= e.material;
    case Effect::friction: return std::abs(std::log(parameter)) >= e.material;
    default: return std::abs(parameter - no_effect_parameter(effect)) >= e.material;
  }
}

std::string separating_experiment(const std::string& a, const std::string& b) {
  const auto pair_is = [&](const char* x, const char* y) { return (a == x && b == y) || (a == y && b == x); };
  // What each pair's signatures share, and the operating change under which they part.
  if (pair_is("gate_leakage", "discharge_coefficient")) {
    return "steps at a small and a large gate opening: a leak adds the same extra opening at both (it dominates "
           "when the gate is nearly closed), a discharge coefficient scales the flow in proportion to the opening";
  }
  if (pair_is("sensor_offset", "downstream_gate")) {
    return "a recording at another flow, or the levels read in still water with the gates closed: an offset "
           "shifts every reading by the same amount at any flow, a downstream gate setting shifts the levels by "
           "an amount that grows with the flow";
  }
  if (pair_is("friction", "downstream_gate") || pair_is("friction", "sensor_offset")) {
    return "recordings at two flows: friction changes the level drop along the pool with the square of the flow, "
           "an offset or a downstream setting shifts the levels more uniformly";
  }
  if (pair_is("lateral_outflow", "discharge_coefficient") || pair_is("lateral_outflow", "gate_leakage")) {
    return "a level sensor upstream of the offtake, or a flow measured at the downstream gate: an outflow along "
           "the pool lowers the downstream flow, a head-gate law changes the inflow itself";
  }
  if (pair_is("sensor_delay", "gate_rate_limit")) {
    return "a step of the command with the gate position logged: a slow gate lags the command in its position, "
           "a sensor delay lags only the readings";
  }
  return "an experiment at another operating point (gate opening and flow), where the two effects change the "
         "levels by different amounts";
}

std::string unsupported_reason(Effect effect, const scenarios::Scenario& s) {
  switch (effect) {
    case Effect::gate_rate_limit:
    case Effect::gate_leakage:
    case Effect::discharge_coefficient:
      return s.head_gate ? "" : "the scenario has no head gate";
    case Effect::friction:
    case Effect::lateral_outflow:
      return s.pools.empty() ? "the scenario has no pools" : "";
    case Effect::downstream_gate:
      return s.downstream.kind == scenarios::DownstreamKind::gate ? "" : "the scenario's downstream end is not a gate";
    default: return "";
  }
}

void apply_effect(Effect effect, double p, scenarios::Scenario& s, double inflow_m3s) {
  if (const std::string why = unsupported_reason(effect, s); !why.empty()) {
    throw std::invalid_argument(std::string(info(effect).name) + ": " + why);
  }
  switch (effect) {
    case Effect::gate_rate_limit:
      s.head_gate->actuator_speed_m_s = std::isfinite(p) ? p * kMm : 0.0;
      break;
    case Effect::gate_leakage: s.head_gate->leakage_m += p * kMm; break;
    case Effect::discharge_coefficient:
      s.head_gate->discharge_coefficient *= p;
      if (s.head_gate->submerged_discharge_coefficient) *s.head_gate->submerged_discharge_coefficient *= p;
      break;
    case Effect::friction:
      for (auto& pool : s.pools) pool.manning_n *= p;
      break;
    case Effect::lateral_outflow: {
      auto& pool = s.pools.front();
      pool.offtakes.push_back({0.5 * pool.length_m, p * inflow_m3s});
      break;
    }
    case Effect::downstream_gate:
      s.downstream.gate.opening_m = std::clamp(s.downstream.gate.opening_m + p * kMm, 0.0,
                                               s.downstream.gate.max_opening_m);
      break;
    case Effect::sensor_quantization: s.sensors.resolution_mm = p; break;
    case Effect::sensor_delay: s.sensors.delay_s += p; break;
    case Effect::sensor_offset: s.sensors.offset_mm += p; break;
  }
}

void apply_effect(Effect effect, double p, SensorModel& m) {
  switch (effect) {
    case Effect::sensor_quantization: m.resolution_mm = p; break;
    case Effect::sensor_delay: m.delay_s += p; break;
    case Effect::sensor_offset: m.offset_mm += p; break;
    default: throw std::invalid_argument(std::string(info(effect).name) + " is not a sensor effect");
  }
}

}  // namespace canalsim::diagnosis
