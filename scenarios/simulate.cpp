#include "scenarios/simulate.hpp"

#include "core/declared_units.hpp"
#include "core/format.hpp"
#include "core/metadata.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "scenarios/design.hpp"
#include "scenarios/prbs.hpp"
#include "scenarios/run_cost.hpp"
#include "scenarios/run_report.hpp"
#include "scenarios/sensors.hpp"
#include "scenarios/settle.hpp"
#include "scenarios/signals.hpp"
#include "solver/steady_state.hpp"

namespace canalsim::scenarios {
namespace {

constexpr double kMm = 1e-3;


solver::SolverOptions solver_options(const NumericsSpec& n) {
  solver::SolverOptions o;
  o.cfl = n.cfl;
  o.limiter = n.van_leer_limiter ? solver::Limiter::van_leer : solver::Limiter::generalised_minmod;
  o.limiter_theta = n.limiter_theta;
  o.order = n.order == 1 ? solver::SpatialOrder::first : solver::SpatialOrder::second;
  o.dry_depth = std::min(n.dry_depth_m, 0.01);
  return o;
}

double automatic_initial_depth(const Scenario& s, const PoolSpec& pool) {
  if (pool.initial_depth_m > 0.0) return pool.initial_depth_m;
  if (pool.target_depth_m > 0.0) return pool.target_depth_m;
  if (s.head_gate) return std::min(0.85 * s.upstream.level_m, 0.9 * pool.wall_height_m);
  if (s.downstream.kind == DownstreamKind::level) return s.downstream.level_m;
  return 0.5 * pool.wall_height_m;
}

solver::ReachSpec reach_spec(const Scenario& s, const PoolSpec& pool) {
  solver::ReachSpec r;
  r.name = pool.name;
  r.length = pool.length_m;
  r.cells = pool.cells;
  r.section = {pool.bottom_width_m, pool.side_slope};
  r.manning_n = pool.manning_n;
  r.bed_elevation.resize(static_cast<std::size_t>(pool.cells));
  for (int i = 0; i < pool.cells; ++i) r.bed_elevation[static_cast<std::size_t>(i)] = cell_bed_elevation(pool, i);
  // First guess of the steady state: the design (backwater) profile with its discharges when
  // there is one (at rest, Newton's line search failed at canal 1's hydraulic jumps and needed
  // continuation marches), else a level pool at rest.
  const bool design = pool.initial_depth_m <= 0.0 && !pool.design_depth_m.empty();
  r.initial_depth = design ? pool.design_depth_m
                           : std::vector<double>(static_cast<std::size_t>(pool.cells), automatic_initial_depth(s, pool));
  if (design) r.initial_discharge = pool.design_discharge_m3s;
  return r;
}

// Fixed offtakes withdraw −Q/dx from their cell; orifices become level-dependent outlets of the
// reach (solver/reach.hpp). An offtake at the pool's downstream end (x_m = length_m) withdraws
// at the end face instead, just upstream of the check. Returns a handle on each offtake for the
// experiment's events.
std::vector<BuiltCanal::Offtake> apply_offtakes(solver::Reach& reach, const PoolSpec& pool) {
  std::vector<BuiltCanal::Offtake> handles;
  for (const auto& off : pool.offtakes) {
    BuiltCanal::Offtake h{offtake_cell(pool, off.x_m), offtake_at_end(pool, off.x_m), -1, off.discharge_m3s,
                          off.coefficient, off.discharge_m3s};
    if (off.kind == OfftakeKind::orifice) {
      h.outlet = h.at_end ? reach.add_end_outlet(off.coefficient, off.invert_m, off.exponent)
                          : reach.add_outlet(h.cell, off.coefficient, off.invert_m, off.exponent);
    } else if (h.at_end) {
      reach.fixed_end_withdrawal() += off.discharge_m3s;
    } else {
      reach.lateral_inflow()[static_cast<std::size_t>(h.cell)] -= off.discharge_m3s / reach.cell_length();
    }
    handles.push_back(h);
  }
  return handles;
}

std::shared_ptr<gates::GateOperation> operation_for(const GateSpec& g,
                                                    const std::function<double(double)>& command) {
  if (!g.controlled) return std::make_shared<gates::GateOperation>(g.opening_m, g.max_opening_m);
  return std::make_shared<gates::GateOperation>(command, g.actuator_speed_m_s, g.max_opening_m,
                                                command(0.0));
}

// An experiment's input file (`kind = "file"`) in mm: its declared units applied.
Recording read_input_file(const InputSpec& in) {
  return in_millimetres(read_recording(in.file, input_series_columns()));
}

// The supply upstream of the head gate. A recorded upstream level comes from the recording being
// replayed, else from the experiment's input file.
std::shared_ptr<gates::Supply> make_supply(const Scenario& s, const ExperimentSpec& e, const Drive& drive,
                                           std::shared_ptr<gates::ReservoirSupply>* reservoir) {
  const UpstreamSpec& u = s.upstream;
  const bool recorded = u.kind == UpstreamKind::recorded || drive.use_recorded_upstream;
  if (recorded) {
    std::optional<Recording> input_file;
    if (!drive.recording && e.input.kind == InputKind::file) input_file = read_input_file(e.input);
    const Recording* levels = drive.recording ? drive.recording : input_file ? &*input_file : nullptr;
    if (!levels) {
      throw InputError(s.source + ": experiment " + e.name + ": upstream.kind = \"recorded\" needs a recording with a " +
                       "y_up_mm column to drive it (an input of kind = \"file\", or a recording replayed)");
    }
    if (!levels->has(columns::upstream_level)) {
      throw InputError(levels->source + ": missing column y_up_mm: upstream.kind = \"recorded\" (" + s.source +
                       ") drives the head gate's upstream level with it");
    }
    // A level of the supply is a depth above the gate's sill: positive, and within 100 m.
    const auto& recorded = levels->column(columns::upstream_level);
    for (std::size_t k = 0; k < recorded.size(); ++k) {
      if (!(recorded[k] > 0.0 && recorded[k] <= 1.0e5)) {
        throw InputError(levels->where(k) + ": y_up_mm = " + format_g(recorded[k]) + " mm: expected an upstream level in " +
                         "(0, 100000] mm to drive upstream.kind = \"recorded\" (" + s.source + ")");
      }
    }
    const auto series = SeriesSignal::from_recording(*levels, columns::upstream_level);
    std::vector<double> t = levels->column(columns::time), y(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) y[i] = series.value(t[i]);
    return std::make_shared<gates::SeriesLevelSupply>(std::move(t), std::move(y));
  }
  if (u.kind == UpstreamKind::reservoir) {
    gates::ReservoirOptions o;
    o.plan_area = u.plan_area_m2;
    o.initial_level = u.level_m;
    o.setpoint = u.level_m;
    o.flow_per_hz = u.pump_m3s_per_hz;
    o.max_frequency = u.max_frequency_hz;
    o.proportional_gain = u.pid_kp;
    o.integral_time = u.pid_ti_s;
    o.derivative_time = u.pid_td_s;
    o.pump_lag = u.pump_lag_s;
    if (const Status status = o.validate(); !status) throw InputError(s.source + ": upstream: " + status.message());
    *reservoir = std::make_shared<gates::ReservoirSupply>(o);
    return *reservoir;
  }
  return std::make_shared<gates::FixedLevelSupply>(u.level_m);
}

std::shared_ptr<solver::Boundary> make_downstream(const Scenario& s, const solver::Reach& last,
                                                  std::shared_ptr<gates::TailGateBoundary>* tail,
                                                  std::shared_ptr<gates::GateOperation>* tail_operation,
                                                  const std::function<double(double)>& command) {
  const DownstreamSpec& d = s.downstream;
  switch (d.kind) {
    case DownstreamKind::gate: {
      const double tail_level = d.tail_level_m;
      *tail_operation = operation_for(d.gate, command);
      *tail = std::make_shared<gates::TailGateBoundary>(
          gate_geometry(d.gate), [tail_level](double) { return tail_level; }, *tail_operation);
      return *tail;
    }
    case DownstreamKind::weir: {
      const double width = d.weir_width_m > 0.0 ? d.weir_width_m : last.section().top_width(0.0);
      return std::make_shared<gates::WeirBoundary>(d.weir_crest_m, d.weir_coefficient, width);
    }
    case DownstreamKind::level:
      return solver::FixedLevelBoundary::depth(d.level_m);
    case DownstreamKind::closed:
      return std::make_shared<solver::WallBoundary>();
    case DownstreamKind::pump:
      return std::make_shared<gates::PumpBoundary>(d.pump_discharge_m3s, d.pump_stop_depth_m);
  }
  throw std::logic_error("unknown downstream kind");
}

// The true values the sensors read, at one time.
struct TrueState {
  double time;
  double upstream_level;    // y_up [m]
  double opening;           // x_up [m]
  double below_gate_depth;  // y_dw [m]
  double end_depth;         // y_dwe [m]
  double discharge;         // through the controlled gate over the last step [m³/s]
  std::vector<double> check_depths;  // at the last cell of each pool, when there are several [m]
};

TrueState interpolate(const TrueState& a, const TrueState& b, double t) {
  const double w = b.time > a.time ? (t - a.time) / (b.time - a.time) : 1.0;
  auto mix = [w](double x, double y) { return x + w * (y - x); };
  std::vector<double> checks(a.check_depths.size());
  for (std::size_t i = 0; i < checks.size(); ++i) checks[i] = mix(a.check_depths[i], b.check_depths[i]);
  return {t, mix(a.upstream_level, b.upstream_level), mix(a.opening, b.opening),
          mix(a.below_gate_depth, b.below_gate_depth), mix(a.end_depth, b.end_depth),
          mix(a.discharge, b.discharge), std::move(checks)};
}

void check(const solver::Status& status, const std::string& what) {
  if (!status) throw std::runtime_error(what + ": " + status.message());
}

// Records what the experiment's u_mm and q_lps follow: the controlled gate, else the first gate
// (head gate, else the first gate between pools); a canal without either records u = 0 and the
// head inflow.
void watch(BuiltCanal& b, std::shared_ptr<gates::GateOperation> op, std::function<double()> discharge,
           double max_opening, bool controlled) {
  if (b.controlled && !controlled) return;  // keep the first gate (or the controlled one)
  if (b.driven) return;
  b.controlled = std::move(op);
  b.controlled_discharge = std::move(discharge);
  b.controlled_max_opening = max_opening;
  b.driven = controlled;
}

std::vector<double> gate_openings(const Scenario& s) {
  std::vector<double> openings;
  if (s.head_gate) openings.push_back(s.head_gate->opening_m);
  for (const auto& g : s.gates) openings.push_back(g.opening_m);
  return openings;
}

}  // namespace

namespace {

// The drive recording's command, resting before t = 0 at the recording's operating point (its
// metadata, as `canalsim simulate` writes it), else at the first command.
class RecordedCommand final : public Signal {
 public:
  explicit RecordedCommand(const Recording& recording)
      : series_(SeriesSignal::from_recording(recording, columns::gate_command, Interpolation::zero_order_hold)) {
    const std::optional<double> rest_mm = metadata_number(recording, "operating_opening_mm");
    rest_ = rest_mm ? *rest_mm * kMm : series_.value(0.0);
  }
  double value(double t) const override { return t < 0.0 ? rest_ : series_.value(t); }
  std::vector<double> jumps(double from, double to) const override {
    std::vector<double> out;
    if (from < 0.0 && to >= 0.0 && series_.value(0.0) != rest_) out.push_back(0.0);
    const std::vector<double> later = series_.jumps(std::max(from, 0.0), to);
    out.insert(out.end(), later.begin(), later.end());
    return out;
  }

 private:
  SeriesSignal series_;
  double rest_ = 0.0;
};

}  // namespace

SignalPtr command_input(const ExperimentSpec& e, const Drive& drive) {
  if (drive.recording) return std::make_shared<RecordedCommand>(*drive.recording);
  const double op = e.operating_opening_mm * kMm;
  const InputSpec& in = e.input;
  switch (in.kind) {
    case InputKind::constant: return std::make_shared<ConstantSignal>(op);
    case InputKind::prbs: {
      PrbsOptions o;
      o.stages = in.prbs_stages;
      o.clock_period = in.prbs_clock_s;
      o.amplitude = in.amplitude_mm * kMm;
      o.operating_point = op;
      o.seed = in.prbs_seed;
      return std::make_shared<PrbsSignal>(o);
    }
    case InputKind::step: return std::make_shared<StepSignal>(op, in.amplitude_mm * kMm, in.start_s);
    case InputKind::ramp: return std::make_shared<RampSignal>(op, in.amplitude_mm * kMm, in.start_s, in.ramp_duration_s);
    case InputKind::file: {
      const Recording rec = read_input_file(in);
      return std::make_shared<SeriesSignal>(
          SeriesSignal::from_recording(rec, columns::gate_command, Interpolation::zero_order_hold));
    }
  }
  throw std::logic_error("command_input: unknown input kind");
}

std::function<double(double)> command_signal(const ExperimentSpec& e, const Drive& drive) {
  SignalPtr signal = command_input(e, drive);
  return [signal](double t) { return signal->value(t); };
}

BuiltCanal build_canal(const Scenario& input, const ExperimentSpec& e, const Drive& drive) {
  const Scenario s = resolve_design(input);  // automatic openings, orifice sizes, design profiles
  BuiltCanal b{solver::Canal(solver_options(s.numerics)), {}, {}, {}, {}, {}, {}, 0.0, false, {}, {}, {}, {}, {}, {}};
  for (const PoolSpec& pool : s.pools) {
    check(b.canal.add_reach(reach_spec(s, pool)), s.source + ": pool '" + pool.name + "'");
    b.offtakes.push_back(apply_offtakes(b.canal.reach(b.canal.reach_count() - 1), pool));
  }
  b.command = command_input(e, drive);
  const auto command = [signal = b.command](double t) { return signal->value(t); };
  if (s.head_gate) {
    b.supply = make_supply(s, e, drive, &b.reservoir);
    auto op = operation_for(*s.head_gate, command);
    b.head_gate = std::make_shared<gates::HeadGateBoundary>(gate_geometry(*s.head_gate), b.supply, op);
    check(b.canal.set_boundary(0, solver::End::upstream, b.head_gate), s.source + ": head_gate");
    auto gate = b.head_gate;
    watch(b, op, [gate] { return gate->last_discharge(); }, s.head_gate->max_opening_m, s.head_gate->controlled);
  } else {
    b.head_inflow = std::make_shared<double>(s.upstream.discharge_m3s);
    auto inflow = b.head_inflow;
    check(b.canal.set_boundary(0, solver::End::upstream,
                               std::make_shared<solver::FixedDischargeBoundary>([inflow](double) { return *inflow; })),
          s.source + ": upstream");
  }
  for (std::size_t i = 0; i < s.gates.size(); ++i) {
    auto op = operation_for(s.gates[i], command);
    auto link = std::make_shared<gates::GateLink>(gate_geometry(s.gates[i]), op);
    b.gate_links.push_back(link);
    check(b.canal.connect(static_cast<int>(i), static_cast<int>(i) + 1, link),
          s.source + ": gates[" + std::to_string(i) + "]");
    watch(b, op, [link] { return link->last_discharge(); }, s.gates[i].max_opening_m, s.gates[i].controlled);
  }
  const int last = b.canal.reach_count() - 1;
  std::shared_ptr<gates::GateOperation> tail_operation;
  check(b.canal.set_boundary(last, solver::End::downstream,
                             make_downstream(s, b.canal.reach(last), &b.tail_gate, &tail_operation, command)),
        s.source + ": downstream");
  if (b.tail_gate && s.downstream.gate.controlled) {
    auto tail = b.tail_gate;
    watch(b, tail_operation, [tail] { return tail->last_discharge(); }, s.downstream.gate.max_opening_m, true);
  }
  check(b.canal.check_ready(), s.source);
  if (!b.controlled) {
    auto inflow = b.head_inflow;
    watch(b, std::make_shared<gates::GateOperation>(0.0, 0.0), [inflow] { return inflow ? *inflow : 0.0; }, 0.0, false);
  }
  b.openings = gate_openings(s);
  for (const auto& p : s.pools) b.check_bed.push_back(p.bed_elevation_m - p.bed_slope * p.length_m);
  return b;
}

double BuiltCanal::check_depth(int pool) const {
  const solver::Reach& r = canal.reach(pool);
  const int n = r.cells();
  const double dry = canal.options().dry_depth;
  double level = r.level(n - 1);
  if (n >= 2 && r.depth(n - 1) > dry && r.depth(n - 2) > dry) level += 0.5 * (level - r.level(n - 2));
  return level - check_bed.at(static_cast<std::size_t>(pool));
}

void apply_event(BuiltCanal& b, const EventSpec& ev) {
  if (ev.inflow_m3s >= 0.0 && b.head_inflow) *b.head_inflow = ev.inflow_m3s;
  if (ev.pool <= 0) return;
  solver::Reach& reach = b.canal.reach(ev.pool - 1);
  BuiltCanal::Offtake& o = b.offtakes.at(static_cast<std::size_t>(ev.pool - 1)).at(static_cast<std::size_t>(ev.offtake - 1));
  if (o.outlet >= 0) {
    // The outlet gate is reset so that it would deliver the new discharge at its design level.
    reach.set_outlet_coefficient(o.outlet, o.design_coefficient * ev.offtake_m3s / std::max(o.design_m3s, 1e-300));
    return;
  }
  if (o.at_end) {
    reach.fixed_end_withdrawal() = std::max(reach.fixed_end_withdrawal() + ev.offtake_m3s - o.current_m3s, 0.0);
  } else {
    reach.lateral_inflow()[static_cast<std::size_t>(o.cell)] += (o.current_m3s - ev.offtake_m3s) / reach.cell_length();
  }
  o.current_m3s = ev.offtake_m3s;
}

namespace {

// An input file that asks the gate for openings it cannot reach, or ends before the experiment
// does, is run as the gate and the hold make it (clipped to the range, the last value held), and
// says so.
void warn_about_input_file(const Scenario& s, const ExperimentSpec& e, const SimulateOptions& options) {
  if (e.input.kind != InputKind::file || options.drive.recording) return;
  const Recording rec = read_input_file(e.input);
  const auto& t = rec.column(columns::time);
  const auto& u = rec.column(columns::gate_command);
  const std::string what = s.source + ": experiment " + e.name + ": input file " + rec.source;
  const auto [lowest, highest] = std::minmax_element(u.begin(), u.end());
  double max_opening_mm = -1.0;
  if (s.head_gate && s.head_gate->controlled) max_opening_mm = s.head_gate->max_opening_m / kMm;
  for (const GateSpec& g : s.gates) {
    if (max_opening_mm < 0.0 && g.controlled) max_opening_mm = g.max_opening_m / kMm;
  }
  if (max_opening_mm >= 0.0 && (*lowest < 0.0 || *highest > max_opening_mm)) {
    warn(options, what + ": u_mm spans " + format_g(*lowest) + " .. " + format_g(*highest) +
                      " mm, outside the gate's range [0, " + format_g(max_opening_mm) + "] mm: the gate stops at its limits");
  }
  if (t.front() > 0.0 || t.back() < e.duration_s) {
    warn(options, what + ": t_s covers " + format_g(t.front()) + " .. " + format_g(t.back()) + " s of the experiment's 0 .. " +
                      format_g(e.duration_s) + " s: the command holds its first and last values outside");
  }
}

// Where the sensors read the canal: y_dw below the gate in the first pool, y_dwe at the end of the
// last, y_check at the check of every pool of a canal of several (BuiltCanal::check_depth).
struct SensorSites {
  int last_pool = 0;
  double below_gate_x = 0.0, end_x = 0.0;
  int checks = 0;
};

SensorSites sensor_sites(const BuiltCanal& b, const SensorSpec& sensors) {
  SensorSites at;
  at.last_pool = b.canal.reach_count() - 1;
  const auto& last = b.canal.reach(at.last_pool);
  at.end_x = sensors.downstream_sensor_x_m < 0.0 ? last.length() - 0.5 * last.cell_length() : sensors.downstream_sensor_x_m;
  at.below_gate_x = std::min(sensors.below_gate_sensor_x_m, b.canal.reach(0).length());
  at.checks = b.canal.reach_count() > 1 ? b.canal.reach_count() : 0;
  return at;
}

// The true state the sensors read, at the canal's current time.
TrueState true_state(const BuiltCanal& b, const SensorSites& at) {
  const double t = b.canal.time();
  std::vector<double> checks(static_cast<std::size_t>(at.checks));
  for (int i = 0; i < at.checks; ++i) checks[static_cast<std::size_t>(i)] = b.check_depth(i);
  return TrueState{t,
                   b.supply ? b.supply->level(t) : 0.0,
                   b.controlled->opening(t),
                   b.canal.sample(0, at.below_gate_x, solver::Quantity::depth),
                   b.canal.sample(at.last_pool, at.end_x, solver::Quantity::depth),
                   b.controlled_discharge(),
                   std::move(checks)};
}

// The run's instruments: the level sensors (each with its own offset and noise seed), the gate's
// position sensor, and a level sensor at every pool's check.
struct Instruments {
  Sensor y_dwe, y_dw, y_up, x_up;
  std::vector<Sensor> y_check;

  void observe(double t, const TrueState& now) {
    y_dwe.observe(t, now.end_depth);
    y_dw.observe(t, now.below_gate_depth);
    y_up.observe(t, now.upstream_level);
    x_up.observe(t, now.opening);
    for (std::size_t i = 0; i < y_check.size(); ++i) y_check[i].observe(t, now.check_depths[i]);
  }
  // Level sensors whose readings lead the command (a negative delay) still owe the last samples.
  void finish(std::size_t samples) {
    for (Sensor* sensor : {&y_dwe, &y_dw, &y_up}) sensor->finish(samples);
    for (Sensor& sensor : y_check) sensor.finish(samples);
  }
};

Instruments make_instruments(const SensorSpec& sensors, int checks) {
  auto level_sensor = [&](std::uint64_t seed_offset, double own_offset_mm = 0.0) {
    SensorOptions o = SensorOptions::defaults_for(SensorKind::level);
    o.sample_period = sensors.period_s;
    o.resolution = sensors.resolution_mm * kMm;
    o.noise_std = sensors.noise_std_mm * kMm;
    o.delay = sensors.delay_s;
    o.offset = (sensors.offset_mm + own_offset_mm) * kMm;
    o.seed = sensors.seed + seed_offset;
    return Sensor(o);
  };
  SensorOptions gate_position = SensorOptions::defaults_for(SensorKind::gate_position);
  gate_position.sample_period = sensors.period_s;
  Instruments out{level_sensor(0, sensors.offset_y_dwe_mm), level_sensor(1, sensors.offset_y_dw_mm),
                  level_sensor(2, sensors.offset_y_up_mm), Sensor(gate_position), {}};
  for (int i = 0; i < checks; ++i) out.y_check.push_back(level_sensor(3 + static_cast<std::uint64_t>(i)));
  return out;
}

// The canal stepped through an experiment. The solver steps freely (no step is cut short to hit
// a sample time); the state at a sample is the linear interpolation in time between the true
// states before and after it. Between steps of ~h/3 the interpolation error is far below the
// 0.05 mm sensor resolution.
class Run {
 public:
  Run(BuiltCanal& b, const ExperimentSpec& e, const SensorSites& at, RunCostGuard& guard)
      : b_(b), e_(e), at_(at), guard_(guard), before_(true_state(b, at)), after_(before_),
        // A step ends just after every jump of the command, so the gate switches when its
        // command does (eq. 16 from that instant), not at the first step boundary after it: up to
        // a step (tens of ms) late, which shifts every response to a switch and makes it jump,
        // not vary smoothly, with the scenario's parameters (calibration and diagnosis
        // differentiate it).
        breaks_(b.command->jumps(b.canal.time(), e.duration_s)) {}

  // The true state at sample time t, stepping the canal past it.
  TrueState state_at(double t) {
    while (after_.time < t) step();
    return interpolate(before_, after_, t);
  }
  double time() const { return after_.time; }

 private:
  void step() {
    // Events take effect at their time exactly: no step crosses one.
    while (next_event_ < e_.events.size() && e_.events[next_event_].t_s <= b_.canal.time() + 1e-9) {
      apply_event(b_, e_.events[next_event_++]);
    }
    const double to_event = next_event_ < e_.events.size() ? e_.events[next_event_].t_s - b_.canal.time()
                                                           : std::numeric_limits<double>::infinity();
    while (next_break_ < breaks_.size() && breaks_[next_break_] <= b_.canal.time()) ++next_break_;
    const double to_break = next_break_ < breaks_.size() ? breaks_[next_break_] - b_.canal.time() + kJustAfter
                                                         : std::numeric_limits<double>::infinity();
    before_ = after_;
    check(b_.canal.step(std::min(to_event, to_break)), "experiment " + e_.name);
    guard_.check(b_.canal.statistics().steps, b_.canal.time(), b_.canal.time() - before_.time);
    after_ = true_state(b_, at_);
  }

  static constexpr double kJustAfter = 1e-9;  // s: the zero-order-hold command takes its new value from t_i on
  BuiltCanal& b_;
  const ExperimentSpec& e_;
  const SensorSites& at_;
  RunCostGuard& guard_;
  TrueState before_, after_;
  std::vector<double> breaks_;
  std::size_t next_event_ = 0, next_break_ = 0;
};

// What the run recorded besides the sensors: the sampling instants, the command and the
// controlled gate's discharge.
struct Logged {
  std::vector<double> t_s, u_mm, q_lps;
};

std::vector<double> in_mm(const std::vector<double>& v) {
  std::vector<double> out(v.size());
  std::transform(v.begin(), v.end(), out.begin(), [](double x) { return x / kMm; });
  return out;
}

// The regime by the paper's conditions (8)/(10) and y_lc of eq. (23), from the recorded
// (measured) levels and opening, as the paper computed its Figure 6.
void add_regime_columns(Recording& rec) {
  const auto& dwe = rec.column(columns::level_downstream_end);
  const auto& xup = rec.column(columns::gate_position);
  const auto& yup = rec.column(columns::upstream_level);
  std::vector<double> y_lc(dwe.size()), regime(dwe.size());
  for (std::size_t k = 0; k < dwe.size(); ++k) {
    // A closed gate has no finite limit; 1e6 mm keeps the file readable (no "inf").
    y_lc[k] = std::min(gates::limit_condition_level(dwe[k] * kMm, xup[k] * kMm) / kMm, 1e6);
    const auto r = gates::classify_regime(yup[k] * kMm, dwe[k] * kMm, xup[k] * kMm);
    regime[k] = r == gates::GateRegime::submerged || r == gates::GateRegime::closed ? static_cast<double>(RegimeCode::submerged)
                                                                                    : static_cast<double>(RegimeCode::free);
  }
  rec.set_column(columns::regime, std::move(regime));
  rec.set_column("y_lc_mm", std::move(y_lc));
}

// The recording of a run: metadata, the run's volume balance, the logged series, every
// instrument's readings in mm, and the regime columns.
Recording recording_of(const Scenario& s, const ExperimentSpec& e, const BuiltCanal& b, double h,
                       const InitialState& initial, const WallWatch& walls, const Logged& logged,
                       const Instruments& instruments) {
  Recording rec;
  rec.source = s.name + "/" + e.name;
  rec.set_meta("scenario", s.name);
  rec.set_meta("experiment", e.name);
  // The opening the canal rested at before t = 0: an input file holds its first command there.
  const double rest_mm = e.input.kind == InputKind::file && b.command ? b.command->value(-1e-9) / kMm : e.operating_opening_mm;
  rec.set_meta("operating_opening_mm", format_g(rest_mm));
  rec.set_meta("sampling_period_s", format_g(h));
  rec.set_meta("generator", "canalsim simulate");
  rec.set_meta("initial_state", initial.description);
  record_run_report(rec, b.canal.total_balance(), b.canal.time(), walls);
  rec.set_column(columns::time, logged.t_s);
  rec.set_column(columns::gate_command, logged.u_mm);
  rec.set_column(columns::gate_position, in_mm(instruments.x_up.values()));
  rec.set_column(columns::upstream_level, in_mm(instruments.y_up.values()));
  rec.set_column(columns::level_below_gate, in_mm(instruments.y_dw.values()));
  rec.set_column(columns::level_downstream_end, in_mm(instruments.y_dwe.values()));
  rec.set_column(columns::discharge, logged.q_lps);
  add_regime_columns(rec);
  for (std::size_t i = 0; i < instruments.y_check.size(); ++i) {
    rec.set_column("y_check" + std::to_string(i + 1) + "_mm", in_mm(instruments.y_check[i].values()));
  }
  return rec;
}

}  // namespace

Recording simulate(const Scenario& s, const ExperimentSpec& e, const SimulateOptions& options) {
  const SensorSpec sensors = e.sensors.value_or(s.sensors);
  check_run_cost(s, e, sensors.period_s, options.allow_long_run);
  warn_about_input_file(s, e, options);
  BuiltCanal b = build_canal(s, e, options.drive);
  const bool fixed_input = e.input.kind == InputKind::constant && !options.drive.recording;
  if (!b.driven && !fixed_input) throw InputError(s.source + ": no gate has controlled = true: nothing to drive");

  // Start from the steady state of the operating point (the command holds its t = 0 value before
  // t = 0): Newton on the discretised equations, or time marching if that fails or is not wanted.
  const auto report = [&](double fraction) {
    if (options.progress) options.progress({std::clamp(fraction, 0.0, 1.0), ""});
  };
  report(0.0);
  RunCostGuard guard(s, e, options.allow_long_run);
  const InitialState initial = settle(b, s, e, options, report, guard);

  // Sampling: every channel read at t_k = k h from the true state, then through its sensor.
  const double h = sensors.period_s;
  const auto samples = static_cast<std::size_t>(std::floor(e.duration_s / h + 1e-9)) + 1;
  const SensorSites at = sensor_sites(b, sensors);
  Instruments instruments = make_instruments(sensors, at.checks);
  Logged logged;
  WallWatch walls(s);
  Run run(b, e, at, guard);
  for (std::size_t k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) * h;
    const TrueState now = run.state_at(t);
    walls.observe(b.canal, run.time());
    instruments.observe(t, now);
    logged.t_s.push_back(t);
    logged.u_mm.push_back(b.controlled->command(t) / kMm);
    logged.q_lps.push_back(now.discharge / kMm);
    if (k % std::max<std::size_t>(1, samples / 100) == 0) {
      report(initial.progress_weight + (1.0 - initial.progress_weight) * t / e.duration_s);
    }
  }
  instruments.finish(samples);
  report(1.0);
  if (options.on_finish) options.on_finish(b);
  return recording_of(s, e, b, h, initial, walls, logged, instruments);
}

}  // namespace canalsim::scenarios
