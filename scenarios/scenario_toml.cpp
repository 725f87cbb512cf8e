#include "scenarios/scenario_toml.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/declared_units.hpp"
#include "core/recording.hpp"
#include "scenarios/toml_table.hpp"

namespace canalsim::scenarios {
namespace {

bool has_controlled_gate(const Scenario& s) {
  bool any = (s.head_gate && s.head_gate->controlled) ||
             (s.downstream.kind == DownstreamKind::gate && s.downstream.gate.controlled);
  for (const auto& g : s.gates) any = any || g.controlled;
  return any;
}

constexpr double kInf = std::numeric_limits<double>::infinity();
const Range kPositiveLength{0.0, 1.0e5, true};
const Range kNonNegative{0.0, kInf};
const Range kPositive{0.0, kInf, true};

GateSpec read_gate(TomlTable t, const GateSpec& defaults) {
  GateSpec g = defaults;
  g.width_m = t.number("width_m", g.width_m, {0.0, 1000.0, true}, "m");
  g.max_opening_m = t.number("max_opening_m", g.max_opening_m, {0.0, 100.0, true}, "m");
  if (t.is_string("opening_m")) {
    if (t.string("opening_m", "") != "auto") {
      t.fail_value("opening_m", "\"" + t.string("opening_m", "") + "\"", "expected a number in [0, max_opening_m] m or \"auto\"");
    }
    g.auto_opening = true;
  } else {
    g.opening_m = t.number("opening_m", g.opening_m, {0.0, g.max_opening_m}, "m");
  }
  g.law = t.choice("law", g.law == GateLaw::swamee ? "swamee" : "simple", {"swamee", "simple"}) == "swamee"
              ? GateLaw::swamee
              : GateLaw::simple;
  g.discharge_coefficient = t.number("discharge_coefficient", g.discharge_coefficient, {0.0, 5.0, true}, "");
  if (t.has("submerged_discharge_coefficient")) {
    g.submerged_discharge_coefficient =
        t.number("submerged_discharge_coefficient", g.submerged_coefficient(), {0.0, 5.0, true}, "");
  }
  g.leakage_m = t.number("leakage_m", g.leakage_m, {0.0, 1.0}, "m");
  g.zero_head_m = t.number("zero_head_m", g.zero_head_m, {0.0, 1.0}, "m (0 = the submerged law as published)");
  g.cd_opening_exponent = t.number("cd_opening_exponent", g.cd_opening_exponent, {-2.0, 2.0}, "(0 = the law as published)");
  g.cd_opening_curvature = t.number("cd_opening_curvature", g.cd_opening_curvature, {-2.0, 2.0}, "(0 = the law as published)");
  g.cd_reference_opening_m = t.number("cd_reference_opening_m", g.cd_reference_opening_m, {0.0, 100.0},
                                      "m (0 = half of max_opening_m)");
  g.border_floor_ratio = t.number("border_floor_ratio", g.border_floor_ratio, {1.0, 2.0, true},
                                  "(the regime border's floor over the tailwater, 1.05 by default)");
  g.actuator_speed_m_s = t.number("actuator_speed_m_s", g.actuator_speed_m_s, {0.0, 100.0}, "m/s (0 = ideal)");
  g.controlled = t.boolean("controlled", g.controlled);
  t.reject_unknown_keys();
  return g;
}

PoolSpec read_pool(TomlTable t) {
  PoolSpec p;
  p.name = t.string("name", p.name);
  p.length_m = t.required_number("length_m", kPositiveLength, "m");
  // At least a millimetre: narrower pools (1e-6 m behind a gate) stall the steady-state Newton
  // solve and, at 1e-300 m, overflow the velocities.
  p.bottom_width_m = t.required_number("bottom_width_m", {0.001, 1000.0}, "m");
  p.side_slope = t.number("side_slope", p.side_slope, {0.0, 10.0}, "(horizontal per vertical)");
  p.wall_height_m = t.number("wall_height_m", p.wall_height_m, {0.0, 100.0, true}, "m");
  p.bed_slope = t.number("bed_slope", p.bed_slope, {-0.1, 0.1}, "m/m");
  p.bed_elevation_m = t.number("bed_elevation_m", p.bed_elevation_m, {-1.0e4, 1.0e4}, "m");
  p.manning_n = t.number("manning_n", p.manning_n, {0.0, 0.2}, "s m^-1/3");
  p.cells = t.integer("cells", p.cells, 4, 1000000);
  p.initial_depth_m = t.number("initial_depth_m", p.initial_depth_m, {0.0, p.wall_height_m}, "m (0 = automatic)");
  p.target_depth_m = t.number("target_depth_m", p.target_depth_m, {0.0, p.wall_height_m}, "m (0 = none)");
  for (auto o : t.tables("offtakes")) {
    OfftakeSpec off;
    off.x_m = o.required_number("x_m", {0.0, p.length_m}, "m (inside the pool)");
    off.discharge_m3s = o.required_number("discharge_m3s", {0.0, 1.0e4}, "m^3/s");
    off.kind = o.choice("kind", "fixed", {"fixed", "orifice"}) == "fixed" ? OfftakeKind::fixed : OfftakeKind::orifice;
    off.invert_m = o.number("invert_m", off.invert_m, {0.0, p.wall_height_m}, "m above the bed");
    off.exponent = o.number("exponent", off.exponent, {0.5, 3.0}, "(power of the head)");
    if (off.kind == OfftakeKind::orifice && !(p.target_depth_m > off.invert_m)) {
      o.fail_value("kind", "\"orifice\"", "expected the pool to have a target_depth_m above the invert_m to size the orifice");
    }
    o.reject_unknown_keys();
    p.offtakes.push_back(off);
  }
  t.reject_unknown_keys();
  return p;
}

UpstreamSpec read_upstream(TomlTable t) {
  UpstreamSpec u;
  const std::string kind = t.choice("kind", "level", {"level", "reservoir", "discharge", "recorded"});
  u.kind = kind == "level"       ? UpstreamKind::level
           : kind == "reservoir" ? UpstreamKind::reservoir
           : kind == "discharge" ? UpstreamKind::discharge
                                 : UpstreamKind::recorded;
  u.level_m = t.number("level_m", u.level_m, {0.0, 100.0, true}, "m");
  u.discharge_m3s = t.number("discharge_m3s", u.discharge_m3s, {0.0, 1.0e5}, "m^3/s");
  // The reservoir's own limits (gates/reservoir.cpp, ReservoirOptions::validate).
  u.plan_area_m2 = t.number("plan_area_m2", u.plan_area_m2, {0.0, 1.0e6, true}, "m^2");
  u.pump_m3s_per_hz = t.number("pump_m3s_per_hz", u.pump_m3s_per_hz, {0.0, 100.0, true}, "m^3/s per Hz");
  u.max_frequency_hz = t.number("max_frequency_hz", u.max_frequency_hz, {0.0, 1000.0, true}, "Hz");
  u.pid_kp = t.number("pid_kp", u.pid_kp, {0.0, 1.0e9}, "Hz/m");
  u.pid_ti_s = t.number("pid_ti_s", u.pid_ti_s, {0.0, 1.0e9, true}, "s");
  u.pid_td_s = t.number("pid_td_s", u.pid_td_s, {0.0, 1.0e6}, "s");
  u.pump_lag_s = t.number("pump_lag_s", u.pump_lag_s, {0.0, 1.0e4}, "s");
  t.reject_unknown_keys();
  return u;
}

DownstreamSpec read_downstream(TomlTable t) {
  DownstreamSpec d;
  const std::string kind = t.choice("kind", "gate", {"gate", "weir", "level", "closed", "pump"});
  d.kind = kind == "gate"     ? DownstreamKind::gate
           : kind == "weir"   ? DownstreamKind::weir
           : kind == "level"  ? DownstreamKind::level
           : kind == "closed" ? DownstreamKind::closed
                              : DownstreamKind::pump;
  if (t.has("gate")) d.gate = read_gate(t.table("gate"), d.gate);
  d.tail_level_m = t.number("tail_level_m", d.tail_level_m, {0.0, 100.0}, "m (0 = free outfall)");
  d.weir_crest_m = t.number("weir_crest_m", d.weir_crest_m, {0.0, 100.0}, "m");
  d.weir_coefficient = t.number("weir_coefficient", d.weir_coefficient, {0.0, 10.0, true}, "m^0.5/s");
  d.weir_width_m = t.number("weir_width_m", d.weir_width_m, {0.0, 1000.0}, "m (0 = channel width)");
  d.level_m = t.number("level_m", d.level_m, {0.0, 100.0, true}, "m");
  d.pump_discharge_m3s = t.number("pump_discharge_m3s", d.pump_discharge_m3s, {0.0, 1.0e5}, "m^3/s");
  d.pump_stop_depth_m = t.number("pump_stop_depth_m", d.pump_stop_depth_m, {0.0, 100.0, true}, "m");
  t.reject_unknown_keys();
  return d;
}

SensorSpec read_sensors(TomlTable t, const SensorSpec& defaults) {
  SensorSpec s = defaults;
  s.period_s = t.number("period_s", s.period_s, {0.0, 3600.0, true}, "s");
  s.resolution_mm = t.number("resolution_mm", s.resolution_mm, {0.0, 100.0}, "mm (0 = none)");
  s.noise_std_mm = t.number("noise_std_mm", s.noise_std_mm, {0.0, 100.0}, "mm");
  s.delay_s = t.number("delay_s", s.delay_s, {-600.0, 600.0}, "s");
  s.offset_mm = t.number("offset_mm", s.offset_mm, {-1000.0, 1000.0}, "mm");
  s.offset_y_up_mm = t.number("offset_y_up_mm", s.offset_y_up_mm, {-1000.0, 1000.0}, "mm");
  s.offset_y_dw_mm = t.number("offset_y_dw_mm", s.offset_y_dw_mm, {-1000.0, 1000.0}, "mm");
  s.offset_y_dwe_mm = t.number("offset_y_dwe_mm", s.offset_y_dwe_mm, {-1000.0, 1000.0}, "mm");
  s.downstream_sensor_x_m = t.number("downstream_sensor_x_m", s.downstream_sensor_x_m, {-1.0, 1.0e5}, "m (-1 = last cell)");
  s.below_gate_sensor_x_m = t.number("below_gate_sensor_x_m", s.below_gate_sensor_x_m, {0.0, 1.0e5}, "m");
  s.seed = t.seed("seed", s.seed);
  t.reject_unknown_keys();
  return s;
}

// A relative path in a scenario file is relative to that file's folder (as a user who keeps the
// scenario beside its data expects), not to the working directory.
std::string beside_scenario(const std::string& scenario_source, const std::string& path) {
  const std::filesystem::path p(path), scenario(scenario_source);
  if (p.is_absolute() || !scenario.has_parent_path() || !std::filesystem::is_regular_file(scenario)) return path;
  return (scenario.parent_path() / p).lexically_normal().string();
}

InputSpec read_input(TomlTable t) {
  InputSpec in;
  const std::string kind = t.choice("kind", "prbs", {"constant", "prbs", "step", "ramp", "file"});
  in.kind = kind == "constant" ? InputKind::constant
            : kind == "prbs"   ? InputKind::prbs
            : kind == "step"   ? InputKind::step
            : kind == "ramp"   ? InputKind::ramp
                               : InputKind::file;
  // A key of another kind would be read and then ignored without a word.
  const struct {
    const char* key;
    std::initializer_list<const char*> kinds;
  } applies[] = {{"stages", {"prbs"}},          {"clock_s", {"prbs"}},         {"seed", {"prbs"}},
                 {"amplitude_mm", {"prbs", "step", "ramp"}}, {"start_s", {"step", "ramp"}},
                 {"ramp_duration_s", {"ramp"}}, {"file", {"file"}}};
  for (const auto& [key, kinds] : applies) {
    if (!t.has(key) || std::find(kinds.begin(), kinds.end(), kind) != kinds.end()) continue;
    std::string which;
    for (const char* k : kinds) which += std::string(which.empty() ? "" : ", ") + "\"" + k + "\"";
    t.fail(key, "does not apply to kind = \"" + kind + "\" (only to kind = " + which + ")");
  }
  in.prbs_stages = t.integer("stages", in.prbs_stages, 2, 20);
  in.prbs_clock_s = t.number("clock_s", in.prbs_clock_s, {0.0, 3600.0, true}, "s");
  in.prbs_seed = t.seed("seed", in.prbs_seed);
  in.amplitude_mm = t.number("amplitude_mm", in.amplitude_mm, {-1000.0, 1000.0}, "mm");
  in.start_s = t.number("start_s", in.start_s, kNonNegative, "s");
  in.ramp_duration_s = t.number("ramp_duration_s", in.ramp_duration_s, kPositive, "s");
  in.file = t.string("file", in.file);
  if (in.kind == InputKind::file) {
    if (in.file.empty()) t.fail("file", "is missing: expected the path of a recording with a u_mm column");
    const std::string given = in.file;
    in.file = beside_scenario(t.file(), given);
    // Read now, so that a missing or malformed series stops the run before any output is written.
    try {
      (void)in_millimetres(read_recording(in.file, input_series_columns()));
    } catch (const InputError& e) {
      t.fail_value("file", "\"" + given + "\"", e.what());
    }
  }
  t.reject_unknown_keys();
  return in;
}

EventSpec read_event(TomlTable t, const Scenario& s, double previous_t) {
  EventSpec ev;
  ev.t_s = t.required_number("t_s", {previous_t, 1.0e7}, "s (events in time order)");
  ev.pool = t.integer("pool", 0, 1, static_cast<int>(s.pools.size()));  // 0: not given
  const int offtakes = ev.pool > 0 ? static_cast<int>(s.pools[static_cast<std::size_t>(ev.pool - 1)].offtakes.size()) : 0;
  if (ev.pool > 0 && offtakes == 0) t.fail_value("pool", std::to_string(ev.pool), "expected a pool with offtakes");
  ev.offtake = t.integer("offtake", 1, 1, std::max(offtakes, 1));
  ev.offtake_m3s = t.number("offtake_m3s", ev.offtake_m3s, {0.0, 1.0e4}, "m^3/s");
  ev.inflow_m3s = t.number("inflow_m3s", ev.inflow_m3s, {0.0, 1.0e5}, "m^3/s");
  if ((ev.pool > 0) != t.has("offtake_m3s")) {
    t.fail(ev.pool > 0 ? "pool" : "offtake_m3s", "expected pool and offtake_m3s together");
  }
  if (t.has("inflow_m3s") && s.upstream.kind != UpstreamKind::discharge) {
    t.fail("inflow_m3s", "expected [upstream] kind = \"discharge\" for an inflow change");
  }
  if (!t.has("inflow_m3s") && ev.pool == 0) t.fail("t_s", "the event changes nothing: expected offtake_m3s or inflow_m3s");
  t.reject_unknown_keys();
  return ev;
}

ExperimentSpec read_experiment(TomlTable t, const Scenario& s) {
  const SensorSpec& scenario_sensors = s.sensors;
  ExperimentSpec e;
  e.name = t.string("name", "");
  if (e.name.empty()) t.fail("name", "is missing: expected a non-empty experiment name");
  // Required when a gate is driven; an experiment with no controlled gate runs at fixed openings.
  e.operating_opening_mm = has_controlled_gate(s)
                               ? t.required_number("operating_opening_mm", {0.0, 1.0e5}, "mm")
                               : t.number("operating_opening_mm", 0.0, {0.0, 1.0e5}, "mm");
  e.duration_s = t.number("duration_s", e.duration_s, {0.0, 1.0e7, true}, "s");
  e.settle_s = t.number("settle_s", e.settle_s, {0.0, 1.0e6}, "s");
  if (t.has("input")) e.input = read_input(t.table("input"));
  if (t.has("sensors")) e.sensors = read_sensors(t.table("sensors"), scenario_sensors);
  for (auto ev : t.tables("events")) {
    e.events.push_back(read_event(ev, s, e.events.empty() ? 0.0 : e.events.back().t_s));
  }
  t.reject_unknown_keys();
  return e;
}

namespace {

// [calibration] as `canalsim calibrate` writes it: the residual left on the baseline, and
// [calibration.std] mapping calibration parameter names to standard deviations. The names are the
// calibration catalog's (checked where the catalog is known, diagnosis/baseline.hpp); here each
// must look like one and carry a number.
void read_calibration(TomlTable t, Scenario& s) {
  s.calibrated_baseline_rms_mm = t.number("baseline_rms_mm", 0.0, {0.0, 1.0e6}, "mm");
  for (const auto& [table, out] : {std::pair{"std", &s.calibrated_std}, std::pair{"std_alone", &s.calibrated_std_alone}}) {
    if (!t.has(table)) continue;
    TomlTable st = t.table(table);
    for (const std::string& name : st.keys()) {
      const bool plausible = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.';
      });
      if (!plausible) st.fail(name, "expected a calibration parameter name (docs/calibration.md)");
      (*out)[name] = st.number(name, 0.0, {0.0, 1.0e6}, "(a standard deviation in the parameter's unit)");
    }
  }
  for (const auto& [table, out] : {std::pair{"baseline_rms", &s.calibrated_baseline_rms_by_channel},
                                   std::pair{"baseline_slow_rms", &s.calibrated_baseline_slow_rms_by_channel}}) {
    if (!t.has(table)) continue;
    TomlTable rms = t.table(table);
    for (const std::string& channel : rms.keys()) {
      if (channel.rfind("y_", 0) != 0 || channel.size() < 6 || channel.compare(channel.size() - 3, 3, "_mm") != 0) {
        rms.fail(channel, "expected a level channel (y_up_mm, y_dw_mm, y_dwe_mm, y_checkN_mm)");
      }
      (*out)[channel] = rms.number(channel, 0.0, {0.0, 1.0e6}, "mm");
    }
  }
  t.reject_unknown_keys();
}

}  // namespace

Scenario read_scenario(TomlTable root, const std::string& source) {
  Scenario s;
  s.source = source;
  s.name = root.string("name", "");
  s.description = root.string("description", "");
  s.upstream = read_upstream(root.table("upstream"));
  if (root.has("head_gate")) s.head_gate = read_gate(root.table("head_gate"), GateSpec{});
  for (auto p : root.tables("pools")) s.pools.push_back(read_pool(p));
  if (s.pools.empty()) root.fail("pools", "missing: expected at least one [[pools]] table (see docs/scenarios.md)");
  for (auto g : root.tables("gates")) {
    s.gates.push_back(read_gate(g, GateSpec{}));
    const std::size_t i = s.gates.size() - 1;
    const bool targets = i + 1 < s.pools.size() && s.pools[i].target_depth_m > 0.0 && s.pools[i + 1].target_depth_m > 0.0;
    if (s.gates.back().auto_opening && !targets) {
      g.fail_value("opening_m", "\"auto\"", "expected target_depth_m on the pools on both sides (pools[" +
                              std::to_string(i) + "] and pools[" + std::to_string(i + 1) + "])");
    }
  }
  if (s.head_gate && s.head_gate->auto_opening && s.pools.front().target_depth_m <= 0.0) {
    auto h = root.table("head_gate");
    h.fail_value("opening_m", "\"auto\"", "expected target_depth_m on pools[0]");
  }
  s.downstream = read_downstream(root.table("downstream"));
  if (s.downstream.gate.auto_opening) {
    auto g = root.table("downstream").table("gate");
    g.fail_value("opening_m", "\"auto\"", "expected a number: the end gate has no automatic opening");
  }
  s.sensors = read_sensors(root.table("sensors"), SensorSpec{});
  {
    auto n = root.table("numerics");
    s.numerics.cfl = n.number("cfl", s.numerics.cfl, {0.0, 1.0, true}, "");
    s.numerics.order = n.integer("order", s.numerics.order, 1, 2);
    s.numerics.van_leer_limiter =
        n.choice("limiter", s.numerics.van_leer_limiter ? "van_leer" : "minmod", {"van_leer", "minmod"}) == "van_leer";
    s.numerics.limiter_theta = n.number("limiter_theta", s.numerics.limiter_theta, {1.0, 2.0}, "(1 = minmod, 2 = monotonised central)");
    s.numerics.dry_depth_m = n.number("dry_depth_m", s.numerics.dry_depth_m, {0.0, 1.0, true}, "m");
    s.numerics.steady_tolerance_m = n.number("steady_tolerance_m", s.numerics.steady_tolerance_m, {0.0, 1.0, true}, "m");
    n.reject_unknown_keys();
  }
  for (auto e : root.tables("experiments")) s.experiments.push_back(read_experiment(e, s));
  if (root.has("calibration")) read_calibration(root.table("calibration"), s);
  root.reject_unknown_keys();
  return s;
}

std::string number(double v) { return format_value(v); }

// Checks that span several keys. The TOML document, when the scenario came from one, lets a
// message name the line of the key it blames: "FILE:LINE: key: what".
struct Validator {
  const Scenario& s;
  const toml::table* document = nullptr;

  [[noreturn]] void invalid(const std::string& key, const std::string& what) const {
    std::string where = s.source;
    if (document) {
      if (const auto node = document->at_path(key)) where += ":" + std::to_string(node.node()->source().begin.line);
    }
    // "key = value: expected ..." when the message starts with the value, as TomlTable writes it.
    throw InputError(where + ": " + key + (what.rfind("= ", 0) == 0 ? " " : ": ") + what);
  }
};

void check_gate_fits(const Validator& v, const GateSpec& g, const PoolSpec& pool, const std::string& key) {
  if (g.max_opening_m > pool.wall_height_m) {
    v.invalid(key + ".max_opening_m", "= " + number(g.max_opening_m) +
                                           " m: expected at most the wall height of pool '" + pool.name +
                                           "' (" + number(pool.wall_height_m) + " m)");
  }
}

}  // namespace

const ExperimentSpec* Scenario::find_experiment(const std::string& wanted) const {
  for (const auto& e : experiments) {
    if (e.name == wanted) return &e;
  }
  return nullptr;
}

static void validate(const Scenario& s, const toml::table* document) {
  const Validator v{s, document};
  if (s.gates.size() + 1 != s.pools.size()) {
    v.invalid("gates", std::to_string(s.gates.size()) + " gates for " + std::to_string(s.pools.size()) +
                            " pools: expected one [[gates]] table between each pair of pools");
  }
  if (s.head_gate) check_gate_fits(v, *s.head_gate, s.pools.front(), "head_gate");
  for (std::size_t i = 0; i < s.gates.size(); ++i) {
    check_gate_fits(v, s.gates[i], s.pools[i + 1], "gates[" + std::to_string(i) + "]");
  }
  if (s.downstream.kind == DownstreamKind::gate) {
    check_gate_fits(v, s.downstream.gate, s.pools.back(), "downstream.gate");
  }
  if (!s.head_gate && s.upstream.kind != UpstreamKind::discharge) {
    v.invalid("upstream.kind", "a level, reservoir or recorded upstream needs a [head_gate]; "
                                "expected kind = \"discharge\" without one");
  }
  int controlled = (s.head_gate && s.head_gate->controlled) ? 1 : 0;
  for (const auto& g : s.gates) controlled += g.controlled ? 1 : 0;
  if (s.downstream.kind == DownstreamKind::gate && s.downstream.gate.controlled) ++controlled;
  if (controlled > 1) v.invalid("controlled", "more than one gate has controlled = true: expected at most one");
  const double last_length = s.pools.back().length_m;
  const auto check_sensor_position = [&](const SensorSpec& sensors, const std::string& key) {
    if (sensors.downstream_sensor_x_m > last_length) {
      v.invalid(key + ".downstream_sensor_x_m", "= " + number(sensors.downstream_sensor_x_m) +
                                                   " m: expected at most the last pool's length (" +
                                                   number(last_length) + " m)");
    }
  };
  check_sensor_position(s.sensors, "sensors");
  for (std::size_t i = 0; i < s.experiments.size(); ++i) {
    if (s.experiments[i].sensors) check_sensor_position(*s.experiments[i].sensors, "experiments[" + std::to_string(i) + "].sensors");
  }
  const GateSpec* driven = nullptr;
  if (s.head_gate && s.head_gate->controlled) driven = &*s.head_gate;
  for (const auto& g : s.gates) if (g.controlled) driven = &g;
  if (s.downstream.kind == DownstreamKind::gate && s.downstream.gate.controlled) driven = &s.downstream.gate;
  for (std::size_t i = 0; i < s.experiments.size(); ++i) {
    const auto& e = s.experiments[i];
    const std::string key = "experiments[" + std::to_string(i) + "]";
    if (!driven && e.input.kind != InputKind::constant) {
      v.invalid(key + ".input.kind", "an experiment with an input signal needs a gate with controlled = true; "
                                      "expected kind = \"constant\" without one");
    }
    const double max_mm = driven ? driven->max_opening_m * 1000.0 : 0.0;
    if (driven && e.operating_opening_mm > max_mm) {
      v.invalid(key + ".operating_opening_mm", "= " + number(e.operating_opening_mm) +
                                                    " mm: expected at most the gate's max_opening_m (" +
                                                    number(max_mm) + " mm)");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (s.experiments[j].name == e.name) v.invalid(key + ".name", "'" + e.name + "' is used twice");
    }
  }
}

void validate(const Scenario& s) { validate(s, nullptr); }

Scenario parse_scenario(const std::string& toml_text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source);
  } catch (const toml::parse_error& e) {
    throw InputError(source + ":" + std::to_string(e.source().begin.line) + ": not valid TOML (" +
                     std::string(e.description()) + "); expected key = value lines and [tables], see docs/scenarios.md");
  }
  Scenario s = read_scenario(TomlTable(root, source, ""), source);
  validate(s, &root);
  return s;
}

Scenario load_scenario(const std::filesystem::path& file) {
  return parse_scenario(read_text_file(file, "scenario file"), file.string());
}

}  // namespace canalsim::scenarios
