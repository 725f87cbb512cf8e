#include "calibration/parameters.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "core/laws.hpp"

namespace canalsim::calibration {
namespace {

using scenarios::Scenario;
constexpr double kMm = 1e-3;
// The share of the samples under the head gate's floored regime border (share_under_floored_border)
// from which the default set fits the floor: a tenth, one operating point of several.
constexpr double kFlooredShareForDefault = 0.1;

Parameter make(std::string name, std::string unit, std::string key, std::string description, double low, double high,
               Transform transform, double step, std::function<double(const Scenario&)> get,
               std::function<void(Scenario&, double)> set, bool sensor_only = false) {
  Parameter p;
  p.name = std::move(name);
  p.unit = std::move(unit);
  p.key = std::move(key);
  p.description = std::move(description);
  p.low = low;
  p.high = high;
  p.transform = transform;
  p.step = step;
  p.sensor_only = sensor_only;
  p.get = std::move(get);
  p.set = std::move(set);
  // Parameters in mm (mm/s) edit keys in m (m/s).
  if (p.unit == "mm" && p.key.size() > 2 && p.key.compare(p.key.size() - 2, 2, "_m") == 0) p.key_scale = kMm;
  if (p.unit == "mm/s") p.key_scale = kMm;
  return p;
}

// Per-pool entries are named "base" for a canal of one pool, "base.i" (1-based) otherwise.
std::string pool_name(const std::string& base, std::size_t i, std::size_t pools) {
  return pools == 1 ? base : base + "." + std::to_string(i + 1);
}

void add_head_gate(const Scenario& s, std::vector<Parameter>& out) {
  if (!s.head_gate) return;
  out.push_back(make("cd_free", "-", "head_gate.discharge_coefficient",
                     "head gate discharge-coefficient multiplier in free flow (Swamee's law, or Cd of eq. 9)", 0.3, 3.0,
                     Transform::log, 0.01, [](const Scenario& x) { return x.head_gate->discharge_coefficient; },
                     [](Scenario& x, double v) {
                       // Pin the submerged one first: unset, it would follow the free one.
                       x.head_gate->submerged_discharge_coefficient = x.head_gate->submerged_coefficient();
                       x.head_gate->discharge_coefficient = v;
                     }));
  out.push_back(make("cd_submerged", "-", "head_gate.submerged_discharge_coefficient",
                     "head gate discharge-coefficient multiplier in submerged flow (gates/sluice_gate.hpp)", 0.3, 3.0,
                     Transform::log, 0.01, [](const Scenario& x) { return x.head_gate->submerged_coefficient(); },
                     [](Scenario& x, double v) { x.head_gate->submerged_discharge_coefficient = v; }));
  out.push_back(make("zero_head_mm", "mm", "head_gate.zero_head_m",
                     "head below which the head gate's submerged law turns linear in the head (gates/sluice_gate.hpp)",
                     0.0, 20.0, Transform::linear, 0.05, [](const Scenario& x) { return x.head_gate->zero_head_m / kMm; },
                     [](Scenario& x, double v) { x.head_gate->zero_head_m = v * kMm; }));
  out.back().low_is_published = true;
  out.push_back(make("cd_opening_exponent", "-", "head_gate.cd_opening_exponent",
                     "exponent β of the head gate's discharge coefficient in the opening, Cd ∝ (a / a_ref)^β "
                     "(gates/sluice_gate.hpp)",
                     -1.0, 1.0, Transform::linear, 0.01, [](const Scenario& x) { return x.head_gate->cd_opening_exponent; },
                     [](Scenario& x, double v) { x.head_gate->cd_opening_exponent = v; }));
  out.push_back(make("cd_opening_curvature", "-", "head_gate.cd_opening_curvature",
                     "curvature γ of the head gate's discharge coefficient in log-log, exp(γ ln²(a / a_ref)) "
                     "(gates/sluice_gate.hpp)",
                     -1.0, 1.0, Transform::linear, 0.01, [](const Scenario& x) { return x.head_gate->cd_opening_curvature; },
                     [](Scenario& x, double v) { x.head_gate->cd_opening_curvature = v; }));
  out.push_back(make("border_floor_ratio", "-", "head_gate.border_floor_ratio",
                     "floor κ of the head gate's regime border over the tailwater, max(y_lc, κ y3): the head "
                     "(κ − 1) y3 at which a wide-open gate's flow frees (gates/sluice_gate.hpp)",
                     1.005, 1.3, Transform::linear, 0.002, [](const Scenario& x) { return x.head_gate->border_floor_ratio; },
                     [](Scenario& x, double v) { x.head_gate->border_floor_ratio = v; }));
  out.push_back(make("actuator_speed_mm_s", "mm/s", "head_gate.actuator_speed_m_s",
                     "head gate actuator speed (paper eq. 16); the scenario's 0 (ideal) is outside the bounds", 0.5,
                     1000.0, Transform::log, 0.02, [](const Scenario& x) { return x.head_gate->actuator_speed_m_s / kMm; },
                     [](Scenario& x, double v) { x.head_gate->actuator_speed_m_s = v * kMm; }));
}

void add_pools(const Scenario& s, std::vector<Parameter>& out) {
  const std::size_t n = s.pools.size();
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(make(pool_name("manning_n", i, n), "s m^-1/3", "pools[" + std::to_string(i + 1) + "].manning_n",
                       "Manning roughness of pool " + s.pools[i].name, 0.002, 0.1, Transform::log, 0.01,
                       [i](const Scenario& x) { return x.pools[i].manning_n; },
                       [i](Scenario& x, double v) { x.pools[i].manning_n = v; }));
  }
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(make(pool_name("bed_slope", i, n), "m/m", "pools[" + std::to_string(i + 1) + "].bed_slope",
                       "bed slope of pool " + s.pools[i].name, -0.01, 0.01, Transform::linear, 1e-5,
                       [i](const Scenario& x) { return x.pools[i].bed_slope; },
                       [i](Scenario& x, double v) { x.pools[i].bed_slope = v; }));
  }
}

void add_downstream(const Scenario& s, std::vector<Parameter>& out) {
  using scenarios::DownstreamKind;
  if (s.downstream.kind == DownstreamKind::gate) {
    const double max_mm = s.downstream.gate.max_opening_m / kMm;
    out.push_back(make("downstream_opening_mm", "mm", "downstream.gate.opening_m", "opening of the downstream gate",
                       0.1, max_mm, Transform::linear, 0.05,
                       [](const Scenario& x) { return x.downstream.gate.opening_m / kMm; },
                       [](Scenario& x, double v) { x.downstream.gate.opening_m = v * kMm; }));
    out.push_back(make("downstream_cd", "-", "downstream.gate.discharge_coefficient",
                       "downstream gate discharge-coefficient multiplier (free and submerged together)", 0.3, 3.0,
                       Transform::log, 0.01, [](const Scenario& x) { return x.downstream.gate.discharge_coefficient; },
                       [](Scenario& x, double v) {
                         auto& g = x.downstream.gate;
                         if (g.submerged_discharge_coefficient) *g.submerged_discharge_coefficient *= v / g.discharge_coefficient;
                         g.discharge_coefficient = v;
                       }));
    out.push_back(make("downstream_zero_head_mm", "mm", "downstream.gate.zero_head_m",
                       "head below which the downstream gate's submerged law turns linear in the head (gates/sluice_gate.hpp)",
                       0.0, 20.0, Transform::linear, 0.05,
                       [](const Scenario& x) { return x.downstream.gate.zero_head_m / kMm; },
                       [](Scenario& x, double v) { x.downstream.gate.zero_head_m = v * kMm; }));
    out.back().low_is_published = true;
    const double wall_mm = (s.pools.empty() ? 1.0 : s.pools.back().wall_height_m) / kMm;
    out.push_back(make("tail_level_mm", "mm", "downstream.tail_level_m", "level beyond the downstream gate", 0.0, wall_mm,
                       Transform::linear, 0.05, [](const Scenario& x) { return x.downstream.tail_level_m / kMm; },
                       [](Scenario& x, double v) { x.downstream.tail_level_m = v * kMm; }));
  }
  if (s.downstream.kind == DownstreamKind::weir) {
    const double wall_mm = (s.pools.empty() ? 1.0 : s.pools.back().wall_height_m) / kMm;
    out.push_back(make("weir_crest_mm", "mm", "downstream.weir_crest_m", "crest of the downstream weir above the bed", 0.0,
                       wall_mm, Transform::linear, 0.05, [](const Scenario& x) { return x.downstream.weir_crest_m / kMm; },
                       [](Scenario& x, double v) { x.downstream.weir_crest_m = v * kMm; }));
  }
}

void add_sensors(std::vector<Parameter>& out) {
  out.push_back(make("offset_mm", "mm", "sensors.offset_mm", "offset shared by every level sensor", -50.0, 50.0,
                     Transform::linear, 0.05, [](const Scenario& x) { return x.sensors.offset_mm; },
                     [](Scenario& x, double v) { x.sensors.offset_mm = v; }, true));
  struct Own {
    const char* name;
    const char* key;
    double scenarios::SensorSpec::*field;
  };
  for (const Own& o : {Own{"offset_y_up_mm", "sensors.offset_y_up_mm", &scenarios::SensorSpec::offset_y_up_mm},
                       Own{"offset_y_dw_mm", "sensors.offset_y_dw_mm", &scenarios::SensorSpec::offset_y_dw_mm},
                       Own{"offset_y_dwe_mm", "sensors.offset_y_dwe_mm", &scenarios::SensorSpec::offset_y_dwe_mm}}) {
    const auto field = o.field;
    out.push_back(make(o.name, "mm", o.key, std::string("offset of the ") + (o.name + 7) + " level sensor", -50.0, 50.0,
                       Transform::linear, 0.05, [field](const Scenario& x) { return x.sensors.*field; },
                       [field](Scenario& x, double v) { x.sensors.*field = v; }, true));
  }
  out.push_back(make("sensor_delay_s", "s", "sensors.delay_s", "delay of the level sensors (negative: they lead the command)", -10.0, 10.0, Transform::linear,
                     0.02, [](const Scenario& x) { return x.sensors.delay_s; },
                     [](Scenario& x, double v) { x.sensors.delay_s = v; }, true));
}

void add_reservoir(const Scenario& s, std::vector<Parameter>& out) {
  if (s.upstream.kind != scenarios::UpstreamKind::reservoir) return;
  out.push_back(make("pump_gain", "m^3/s/Hz", "upstream.pump_m3s_per_hz", "pump flow per Hz of drive frequency", 1e-7,
                     1e-2, Transform::log, 0.01, [](const Scenario& x) { return x.upstream.pump_m3s_per_hz; },
                     [](Scenario& x, double v) { x.upstream.pump_m3s_per_hz = v; }));
  out.push_back(make("pid_kp", "Hz/m", "upstream.pid_kp", "proportional gain of the pump's level PID", 1.0, 1e6,
                     Transform::log, 0.01, [](const Scenario& x) { return x.upstream.pid_kp; },
                     [](Scenario& x, double v) { x.upstream.pid_kp = v; }));
  out.push_back(make("pid_ti_s", "s", "upstream.pid_ti_s", "integral time of the pump's level PID", 0.01, 1000.0,
                     Transform::log, 0.01, [](const Scenario& x) { return x.upstream.pid_ti_s; },
                     [](Scenario& x, double v) { x.upstream.pid_ti_s = v; }));
  // Linear from 0, the ideal pump. Its cost is not monotone from there: a lag shorter than the
  // truth's first rings the reservoir's loop out of phase with it (op1 of a 2 s truth: y_up 3.19 mm
  // RMS off with no lag, 3.36 mm with 0.5 s, 0.86 mm with 1.8 s), so a run from 0 stays there.
  out.push_back(make("pump_lag_s", "s", "upstream.pump_lag_s", "lag of the pump's flow behind its drive", 0.0, 60.0,
                     Transform::linear, 0.05, [](const Scenario& x) { return x.upstream.pump_lag_s; },
                     [](Scenario& x, double v) { x.upstream.pump_lag_s = v; }));
  out.back().scan = {0.25, 0.5, 1.0, 2.0, 4.0, 8.0};
}

// The share of the recordings' samples in which the head gate runs under the floor of its regime
// border (gates/sluice_gate.hpp): Swamee's y_lc (paper eq. 23) below κ y3 and the upstream level
// between the tail and κ y3, read from the gate's recorded position (else its command) and the
// levels on either side of it. There the floor sets the submergence factor and its slope in the
// tail; elsewhere it changes nothing, and fitting it would leave the fit a parameter the
// recordings do not determine.
double share_under_floored_border(const Scenario& s, const std::vector<Recording>& recordings) {
  if (!s.head_gate || s.head_gate->law != scenarios::GateLaw::swamee) return 0.0;
  const double kappa = s.head_gate->border_floor_ratio;
  std::size_t under = 0, samples = 0;
  for (const Recording& r : recordings) {
    const char* opening = r.has(columns::gate_position) ? columns::gate_position : columns::gate_command;
    if (!r.has(opening) || !r.has(columns::upstream_level) || !r.has(columns::level_below_gate)) return 0.0;
    const auto& a = r.column(opening);
    const auto& y1 = r.column(columns::upstream_level);
    const auto& y3 = r.column(columns::level_below_gate);
    for (std::size_t i = 0; i < a.size(); ++i) {
      ++samples;
      const double floor = kappa * y3[i];
      if (a[i] > 0.0 && y1[i] > y3[i] && y1[i] < floor && laws::free_flow_limit_level(y3[i], a[i]) < floor) ++under;
    }
  }
  return samples == 0 ? 0.0 : static_cast<double>(under) / static_cast<double>(samples);
}

}  // namespace

double Parameter::to_search(double value) const { return transform == Transform::log ? std::log(value) : value; }
double Parameter::from_search(double z) const { return transform == Transform::log ? std::exp(z) : z; }

std::vector<Parameter> parameter_catalog(const Scenario& s) {
  std::vector<Parameter> out;
  add_head_gate(s, out);
  add_pools(s, out);
  add_downstream(s, out);
  add_sensors(out);
  add_reservoir(s, out);
  return out;
}

std::string parameter_names(const std::vector<Parameter>& catalog) {
  std::string names;
  for (const auto& p : catalog) names += (names.empty() ? "" : ", ") + p.name;
  return names;
}

std::vector<std::string> default_parameters(const Scenario& s, const std::vector<Recording>& recordings,
                                            bool upstream_replayed) {
  std::vector<std::string> names;
  if (s.head_gate) names.insert(names.end(), {"cd_free", "cd_submerged"});
  for (std::size_t i = 0; i < s.pools.size(); ++i) names.push_back(pool_name("manning_n", i, s.pools.size()));
  if (s.downstream.kind == scenarios::DownstreamKind::gate) {
    names.insert(names.end(), {"downstream_opening_mm", "downstream_zero_head_mm"});
  }
  if (s.downstream.kind == scenarios::DownstreamKind::weir) names.push_back("weir_crest_mm");
  if (share_under_floored_border(s, recordings) >= kFlooredShareForDefault) names.push_back("border_floor_ratio");
  auto all_have = [&](const char* column) {
    return !recordings.empty() &&
           std::all_of(recordings.begin(), recordings.end(), [&](const Recording& r) { return r.has(column); });
  };
  if (all_have(columns::upstream_level) && !upstream_replayed) names.push_back("offset_y_up_mm");
  if (all_have(columns::level_below_gate)) names.push_back("offset_y_dw_mm");
  if (all_have(columns::level_downstream_end)) names.push_back("offset_y_dwe_mm");
  return names;
}

std::vector<std::string> chosen_parameters(const std::vector<std::string>& given, std::vector<std::string> defaults) {
  const auto added = [](const std::string& spec) { return !spec.empty() && spec.front() == '+'; };
  const auto count = static_cast<std::size_t>(std::count_if(given.begin(), given.end(), added));
  if (count == 0) return given.empty() ? defaults : given;
  if (count != given.size()) {
    throw InputError("--params: '" + *std::find_if_not(given.begin(), given.end(), added) + "' and '" +
                     *std::find_if(given.begin(), given.end(), added) +
                     "' mixed (expected every parameter named, or +NAME for each one added to the default set)");
  }
  const auto name_of = [](const std::string& spec) { return spec.substr(0, spec.find(':')); };
  for (const std::string& spec : given) {
    const std::string bare = spec.substr(1);
    const auto same = std::find_if(defaults.begin(), defaults.end(), [&](const std::string& d) { return name_of(d) == name_of(bare); });
    if (same != defaults.end()) {
      *same = bare;
    } else {
      defaults.push_back(bare);
    }
  }
  return defaults;
}

namespace {

// "x" as a finite number, or InputError naming the parameter spec.
double bound_of(const std::string& text, const std::string& spec) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || !std::isfinite(v)) {
    throw InputError("--params: '" + spec + "': bound '" + text + "' is not a number (expected NAME or NAME:LOW:HIGH)");
  }
  return v;
}

}  // namespace

std::vector<Parameter> select_parameters(const Scenario& s, const std::vector<std::string>& specs) {
  const std::vector<Parameter> catalog = parameter_catalog(s);
  std::vector<Parameter> chosen;
  std::set<std::string> seen;
  if (specs.empty()) throw InputError("--params: no parameter named (expected some of " + parameter_names(catalog) + ")");
  for (const auto& spec : specs) {
    const std::size_t colon = spec.find(':');
    const std::string name = spec.substr(0, colon);
    const auto it = std::find_if(catalog.begin(), catalog.end(), [&](const Parameter& p) { return p.name == name; });
    if (it == catalog.end()) {
      throw InputError("--params: unknown parameter '" + name + "' for scenario " + s.source + " (expected one of " +
                       parameter_names(catalog) + ")");
    }
    if (!seen.insert(name).second) throw InputError("--params: parameter '" + name + "' named twice");
    Parameter p = *it;
    if (colon != std::string::npos) {
      const std::string rest = spec.substr(colon + 1);
      const std::size_t second = rest.find(':');
      if (second == std::string::npos) {
        throw InputError("--params: '" + spec + "': expected NAME:LOW:HIGH");
      }
      p.low = bound_of(rest.substr(0, second), spec);
      p.high = bound_of(rest.substr(second + 1), spec);
      if (!(p.low < p.high) || (p.transform == Transform::log && !(p.low > 0.0))) {
        throw InputError("--params: '" + spec + "': expected LOW < HIGH" +
                         (p.transform == Transform::log ? std::string(" and LOW > 0 (searched in log)") : ""));
      }
    }
    const double start = p.get(s);
    if (!(start >= p.low && start <= p.high)) {
      throw InputError("--params: " + name + " starts at " + format_g(start) + " " + p.unit + " (" + p.key + " of " +
                       s.source + "), outside its bounds [" + format_g(p.low) + ", " + format_g(p.high) + "]");
    }
    chosen.push_back(std::move(p));
  }
  return chosen;
}

}  // namespace canalsim::calibration
