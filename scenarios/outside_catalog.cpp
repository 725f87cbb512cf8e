#include "scenarios/outside_catalog.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "scenarios/design.hpp"
#include "scenarios/signals.hpp"

namespace canalsim::scenarios {
namespace {

constexpr double kMm = 1e-3;
// Strictly before the input starts: where simulate() holds the command at its operating point.
constexpr double kBeforeInput = -1e-9;

// One play-operator update: the output pushed to within half the width of the input.
double play(double previous, double input, double half_width) {
  return std::clamp(previous, input - half_width, input + half_width);
}

// The gate the experiment drives, as the simulator picks it (simulate.cpp, watch): the head gate,
// else the first controlled gate between pools, else the downstream gate.
const GateSpec& controlled_gate(const Scenario& s, const ExperimentSpec& e) {
  if (s.head_gate && s.head_gate->controlled) return *s.head_gate;
  for (const GateSpec& g : s.gates) {
    if (g.controlled) return g;
  }
  if (s.downstream.kind == DownstreamKind::gate && s.downstream.gate.controlled) return s.downstream.gate;
  throw InputError(s.source + ": experiment " + e.name + ": no gate has controlled = true: no drive to put a backlash in");
}

// The rate-independent play only reproduces a command that holds each value; a ramp would need
// its path, which a drive of targets cannot carry.
void require_piecewise_constant(const Scenario& s, const ExperimentSpec& e, const Drive& drive) {
  if (!drive.recording && e.input.kind == InputKind::ramp) {
    throw InputError(s.source + ": experiment " + e.name + ": input kind = \"ramp\": a gate backlash needs a " +
                     "piecewise-constant command (constant, prbs, step or file)");
  }
}

// A move of the gate: from `time` on it heads for `opening` [m].
struct GateMove {
  double time;
  double opening;
};

// The motor and the gate behind its play, followed through the command's constant pieces.
struct Drivetrain {
  double motor;
  double gate;
  double half_play;
  double speed;  // of the motor [m/s]; <= 0 = ideal

  // The command `target` holds over [start, end): the motor travels towards it (eq. 16) and
  // pushes the gate once it has crossed the dead travel to the gate's side of the play. Returns
  // the gate's move, if any.
  std::optional<GateMove> hold(double target, double start, double end) {
    const bool ideal = !(speed > 0.0);
    const double direction = target > motor ? 1.0 : -1.0;
    const double travel = ideal ? std::abs(target - motor) : std::min(std::abs(target - motor), speed * (end - start));
    const double motor_end = motor + direction * travel;
    const double gate_end = play(gate, motor_end, half_play);
    std::optional<GateMove> move;
    if (gate_end != gate) {
      // The motor engages the gate at gate + direction · b/2, having travelled `dead` to get there.
      const double dead = std::max(direction * (gate + direction * half_play - motor), 0.0);
      const double engaged = ideal ? start : start + dead / speed;
      if (engaged < end) {
        move = GateMove{engaged, gate_end};
        gate = gate_end;
      }
    }
    motor = motor_end;
    return move;
  }
};

// The gate's moves under a piecewise-constant command over (kBeforeInput, until].
std::vector<GateMove> backlashed_moves(const Signal& command, const GateSpec& g, double width, double until) {
  const auto clamped = [&](double t) { return std::clamp(command.value(t), 0.0, g.max_opening_m); };
  const double rest = clamped(kBeforeInput);
  Drivetrain drivetrain{rest, rest, 0.5 * width, g.actuator_speed_m_s};
  const std::vector<double> jumps = command.jumps(kBeforeInput, until);
  std::vector<GateMove> moves;
  for (std::size_t i = 0; i < jumps.size(); ++i) {
    const double end = i + 1 < jumps.size() ? jumps[i + 1] : std::numeric_limits<double>::infinity();
    if (auto move = drivetrain.hold(clamped(jumps[i]), jumps[i], end)) moves.push_back(*move);
  }
  return moves;
}

// The moves as a drive recording: a row at t = 0 with the target in force then, one per later
// move.
Recording drive_recording(const std::vector<GateMove>& moves, double rest, const std::string& source) {
  std::vector<double> t{0.0}, u{rest / kMm};
  for (const GateMove& move : moves) {
    if (move.time <= 0.0) {
      u.back() = move.opening / kMm;
    } else {
      t.push_back(move.time);
      u.push_back(move.opening / kMm);
    }
  }
  Recording rec;
  rec.source = source + " (gate behind its backlash)";
  rec.set_meta("operating_opening_mm", format_g(rest / kMm, 17));
  rec.set_column(columns::time, std::move(t));
  rec.set_column(columns::gate_command, std::move(u));
  return rec;
}

// The reference state of a seepage: the depth at each outlet's cell and the pool's inflow in the
// steady state of the reference experiment's operating point.
struct ReferenceState {
  std::vector<double> depth;  // [m], per outlet
  double inflow = 0.0;        // [m³/s]
};

ReferenceState reference_state(const Scenario& s, const ExperimentSpec& reference, int pool,
                               const std::vector<int>& cells) {
  ExperimentSpec held = reference;
  held.input.kind = InputKind::constant;
  held.events.clear();
  // The shortest run simulate() records, two samples; from the steady state under a constant
  // command the canal stays there.
  held.duration_s = held.sensors.value_or(s.sensors).period_s;
  ReferenceState state;
  SimulateOptions options;
  options.on_finish = [&](const BuiltCanal& b) {
    const solver::Reach& reach = b.canal.reach(pool);
    for (int cell : cells) state.depth.push_back(reach.depth(cell));
    state.inflow = reach.discharge().front();
  };
  simulate(s, held, options);
  return state;
}

void check_seepage_options(double share, const DepthSeepageOptions& o, const Scenario& s) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("add_depth_seepage: " + what); };
  if (!(share >= 0.0 && share < 1.0)) fail("share = " + format_g(share) + ": expected a value in [0, 1)");
  if (o.pool < 0 || o.pool >= static_cast<int>(s.pools.size())) fail("pool = " + std::to_string(o.pool) + ": no such pool");
  if (o.outlets < 1 || o.outlets > s.pools[static_cast<std::size_t>(o.pool)].cells) {
    fail("outlets = " + std::to_string(o.outlets) + ": expected 1 to the pool's cells");
  }
  if (!(o.exponent >= 0.5 && o.exponent <= 3.0)) fail("exponent = " + format_g(o.exponent) + ": expected a value in [0.5, 3]");
  if (!(o.head_mm > 0.0 && std::isfinite(o.head_mm))) fail("head_mm = " + format_g(o.head_mm) + ": expected a value > 0");
}

const ExperimentSpec& seepage_reference(const Scenario& s, const std::string& name) {
  if (name.empty() && !s.experiments.empty()) return s.experiments.front();
  if (const ExperimentSpec* e = s.find_experiment(name)) return *e;
  throw InputError(s.source + ": add_depth_seepage: no experiment '" + name + "' to take the reference state from");
}

}  // namespace

std::vector<double> play_operator(const std::vector<double>& command, double width, double initial) {
  if (!(std::isfinite(width) && width >= 0.0)) {
    throw std::invalid_argument("play_operator: width = " + format_g(width) + ": expected a finite value >= 0");
  }
  if (!std::isfinite(initial)) throw std::invalid_argument("play_operator: initial output not finite");
  std::vector<double> out(command.size());
  double previous = initial;
  for (std::size_t k = 0; k < command.size(); ++k) out[k] = previous = play(previous, command[k], 0.5 * width);
  return out;
}

Recording backlash_drive(const Scenario& s, const ExperimentSpec& e, double backlash_mm, const Drive& drive) {
  if (!(std::isfinite(backlash_mm) && backlash_mm >= 0.0)) {
    throw InputError(s.source + ": experiment " + e.name + ": backlash = " + format_g(backlash_mm) +
                     " mm: expected a finite value >= 0");
  }
  require_piecewise_constant(s, e, drive);
  const GateSpec& gate = controlled_gate(s, e);
  const SignalPtr command = command_input(e, drive);
  const double rest = std::clamp(command->value(kBeforeInput), 0.0, gate.max_opening_m);
  const auto moves = backlashed_moves(*command, gate, backlash_mm * kMm, e.duration_s);
  return drive_recording(moves, rest, s.name + "/" + e.name);
}

Recording simulate_with_backlash(const Scenario& s, const ExperimentSpec& e, double backlash_mm,
                                 const SimulateOptions& options, const Simulator& simulator) {
  if (options.drive.use_recorded_upstream || s.upstream.kind == UpstreamKind::recorded) {
    throw InputError(s.source + ": experiment " + e.name + ": a gate backlash drives the gate with a recording of " +
                     "its own; it cannot also replay the upstream level (upstream.kind = \"recorded\")");
  }
  const Recording drive = backlash_drive(s, e, backlash_mm, options.drive);
  const SignalPtr command = command_input(e, options.drive);
  SimulateOptions run = options;
  run.drive.recording = &drive;
  Recording rec = simulator ? simulator(s, e, run) : simulate(s, e, run);
  // What the logger records: the command, clamped to the gate's range as simulate() records it.
  const double max_opening = controlled_gate(s, e).max_opening_m;
  std::vector<double> u;
  for (double t : rec.column(columns::time)) u.push_back(std::clamp(command->value(t), 0.0, max_opening) / kMm);
  rec.set_column(columns::gate_command, std::move(u));
  return rec;
}

void add_depth_seepage(Scenario& s, double share, const DepthSeepageOptions& o) {
  check_seepage_options(share, o, s);
  if (share == 0.0) return;
  const ExperimentSpec reference = seepage_reference(s, o.reference_experiment);
  PoolSpec& pool = s.pools[static_cast<std::size_t>(o.pool)];
  std::vector<double> x;
  std::vector<int> cells;
  for (int k = 0; k < o.outlets; ++k) {
    x.push_back((k + 0.5) * pool.length_m / o.outlets);
    cells.push_back(offtake_cell(pool, x.back()));
  }
  const ReferenceState ref = reference_state(s, reference, o.pool, cells);
  const double head = o.head_mm * kMm;
  for (double depth : ref.depth) {
    if (!(depth > head)) {
      throw std::invalid_argument("add_depth_seepage: head_mm = " + format_g(o.head_mm) + ": expected it below the " +
                                  "reference depth at every outlet (" + format_g(depth / kMm) + " mm)");
    }
  }
  const double outlet_share = share * ref.inflow / o.outlets;
  for (int k = 0; k < o.outlets; ++k) {
    OfftakeSpec outlet;
    outlet.x_m = x[static_cast<std::size_t>(k)];
    outlet.kind = OfftakeKind::orifice;
    outlet.exponent = o.exponent;
    outlet.invert_m = ref.depth[static_cast<std::size_t>(k)] - head;
    outlet.discharge_m3s = outlet_share;  // at the reference level
    outlet.coefficient = outlet_share / std::pow(head, o.exponent);
    pool.offtakes.push_back(outlet);
  }
}

}  // namespace canalsim::scenarios
