// Assembly of the state-space model at an experiment's steady state (linearize.hpp). The
// frequency response, gain, poles and delay are in response.cpp.
#include "linearize/linearize.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>

#include "core/errors.hpp"
#include "gates/reservoir.hpp"
#include "scenarios/simulate.hpp"
#include "solver/rates_jacobian.hpp"
#include "solver/steady_state.hpp"

namespace canalsim::linearize {
namespace {

using scenarios::BuiltCanal;
using solver::End;

// Forward-difference step of the canal's unknowns (as the steady-state Newton's Jacobian), and
// central-difference step of the few columns probed one by one (inputs, reservoir states, cells
// next to the output and the head gate), both relative to the unknown's typical size.
constexpr double kJacobianStep = 1e-7;
constexpr double kProbeStep = 1e-6;

// Where the input acts, found before the (costlier) steady state so that bad choices fail fast.
struct InputHandle {
  std::function<void(double)> set;  // sets the input's value
  double value = 0.0;               // at the operating point
  double scale = 0.0;               // typical size, for the difference step
};

InputHandle find_input(BuiltCanal& b, const scenarios::Scenario& s, const InputChoice& in) {
  switch (in.kind) {
    case InputKind::gate: {
      if (!b.head_gate && b.gate_links.empty()) {
        throw InputError("--input gate: scenario '" + s.name + "' has no gate; allowed: " +
                         std::string(b.head_inflow ? "inflow, " : "") + "offtake:I");
      }
      // The controlled gate (else the first) follows a value the linearisation perturbs. At the
      // linearisation point the actuator has arrived, so its rate limit (paper eq. 16) is
      // inactive for inputs slower than speed/amplitude: the gate follows the command exactly.
      auto command = std::make_shared<double>(b.controlled->opening(b.canal.time()));
      b.controlled->set_command([command](double) { return *command; });
      auto op = b.controlled;
      auto* canal = &b.canal;
      return {[command, op, canal](double v) {
                *command = v;
                op->reset(canal->time(), v);
              },
              *command, std::max(*command, 1e-3 * b.controlled_max_opening)};
    }
    case InputKind::inflow: {
      if (!b.head_inflow) {
        throw InputError("--input inflow: scenario '" + s.name +
                         "' has no imposed inflow (upstream.kind = \"discharge\"); allowed: gate, offtake:I");
      }
      auto inflow = b.head_inflow;
      return {[inflow](double v) { *inflow = v; }, *inflow, std::max(std::abs(*inflow), 1e-6)};
    }
    case InputKind::offtake: {
      int count = 0;
      for (std::size_t pool = 0; pool < b.offtakes.size(); ++pool) {
        for (std::size_t k = 0; k < b.offtakes[pool].size(); ++k) {
          if (++count != in.offtake) continue;
          const auto& o = b.offtakes[pool][k];
          const double value = o.outlet >= 0 ? o.design_m3s : o.current_m3s;
          auto* built = &b;
          const int pool_number = static_cast<int>(pool) + 1, offtake_number = static_cast<int>(k) + 1;
          return {[built, pool_number, offtake_number](double v) {
                    scenarios::EventSpec event;
                    event.pool = pool_number;
                    event.offtake = offtake_number;
                    event.offtake_m3s = v;
                    scenarios::apply_event(*built, event);
                  },
                  value, std::max(std::abs(value), 1e-6)};
        }
      }
      throw InputError("--input offtake:" + std::to_string(in.offtake) + ": scenario '" + s.name + "' has " +
                       (count == 0 ? std::string("no offtake") : "offtakes 1.." + std::to_string(count)));
    }
  }
  throw std::logic_error("unknown input kind");
}

int first_cell(const solver::Canal& canal, int reach) {
  int c = 0;
  for (int r = 0; r < reach; ++r) c += canal.reach(r).cells();
  return c;
}

// The output: its value for the canal's current (evaluated) state, and the cells it reads.
struct OutputHandle {
  std::function<double()> value;
  std::vector<int> cells;  // global cell indices whose unknowns it depends on
  bool level = true;       // a level sensor (its pure delay applies)
};

std::vector<int> cells_around(const solver::Canal& canal, int reach, int first, int last) {
  std::vector<int> cells;
  const int offset = first_cell(canal, reach), n = canal.reach(reach).cells();
  for (int i = std::max(first, 0); i <= std::min(last, n - 1); ++i) cells.push_back(offset + i);
  return cells;
}

// The reach whose upstream face is the controlled gate (head gate: reach 0; gate link i: reach
// i + 1); with no gate, reach 0's upstream face passes the head inflow.
int controlled_gate_reach(const BuiltCanal& b) {
  for (std::size_t i = 0; i < b.gate_links.size(); ++i) {
    if (&b.gate_links[i]->operation() == b.controlled.get()) return static_cast<int>(i) + 1;
  }
  return 0;
}

OutputHandle find_output(BuiltCanal& b, const scenarios::Scenario& s, const scenarios::SensorSpec& sensors,
                         const OutputChoice& out) {
  solver::Canal& canal = b.canal;
  const int last = canal.reach_count() - 1;
  // The cell interpolated from at x (Canal::sample: linear between cell centres).
  auto sampled_cells = [&](int reach, double x) {
    const solver::Reach& r = canal.reach(reach);
    const double pos = std::clamp(x / r.cell_length() - 0.5, 0.0, static_cast<double>(r.cells() - 1));
    const int i = std::min(static_cast<int>(pos), r.cells() - 2);
    return cells_around(canal, reach, i, i + 1);
  };
  switch (out.kind) {
    case OutputKind::y_dwe: {
      const solver::Reach& r = canal.reach(last);
      const double x = sensors.downstream_sensor_x_m < 0.0 ? r.length() - 0.5 * r.cell_length()
                                                           : std::min(sensors.downstream_sensor_x_m, r.length());
      return {[&canal, last, x] { return canal.sample(last, x, solver::Quantity::depth); }, sampled_cells(last, x), true};
    }
    case OutputKind::y_dw: {
      const double x = std::min(sensors.below_gate_sensor_x_m, canal.reach(0).length());
      return {[&canal, x] { return canal.sample(0, x, solver::Quantity::depth); }, sampled_cells(0, x), true};
    }
    case OutputKind::q: {
      const int reach = controlled_gate_reach(b);
      std::vector<int> cells = cells_around(canal, reach, 0, 2);
      if (reach > 0) {
        const int n = canal.reach(reach - 1).cells();
        for (int c : cells_around(canal, reach - 1, n - 3, n - 1)) cells.push_back(c);
      }
      return {[&canal, reach] { return canal.end_face_discharge(reach, End::upstream); }, cells, false};
    }
    case OutputKind::y_check: {
      if (out.check < 1 || out.check > canal.reach_count()) {
        throw InputError("--output y_check" + std::to_string(out.check) + ": scenario '" + s.name + "' has pools 1.." +
                         std::to_string(canal.reach_count()) + "; allowed: y_dwe, y_dw, q, y_check1..y_check" +
                         std::to_string(canal.reach_count()));
      }
      const int pool = out.check - 1, n = canal.reach(pool).cells();
      const BuiltCanal* built = &b;
      return {[built, pool] { return built->check_depth(pool); }, cells_around(canal, pool, n - 2, n - 1), true};
    }
  }
  throw std::logic_error("unknown output kind");
}

// The reservoir feeding the head gate (gates/reservoir.hpp), linearised in continuous time with
// its PID unsaturated: y = V/A_p, e = y_set − y,
//   f = (K_p e + I + K_p T_d Q/A_p) / (1 + K_p T_d k_q / A_p)   (derivative on ẏ = (k_q f − Q)/A_p)
//   dV/dt = k_q f − Q,     dI/dt = K_p e / T_i        (I in Hz, as the reservoir keeps it)
// where Q is the head gate's discharge. A saturated pump holds f: V alone, dV/dt = k_q f − Q.
// A pump with a lag τ adds its flow Q_p as the last state:
//   f = K_p (e − T_d (Q_p − Q)/A_p) + I,   dV/dt = Q_p − Q,   dQ_p/dt = (k_q f − Q_p) / τ
// (f held when saturated).
struct ReservoirRows {
  const gates::ReservoirOptions* o = nullptr;
  bool saturated = false;
  bool lagged() const { return o && o->pump_lag > 0.0; }
  int states() const { return o ? 1 + (saturated ? 0 : 1) + (lagged() ? 1 : 0) : 0; }
  int integral_state() const { return 1; }                         // when not saturated
  int pump_state() const { return saturated ? 1 : 2; }              // when lagged
  // d(dV/dt), d(dI/dt), d(dQ_p/dt) for a column that changes Q by dq, V by dv, I by di, Q_p by dp,
  // in the order of the states.
  std::array<double, 3> rows(double dq, double dv, double di, double dp) const {
    const double de = -dv / o->plan_area;
    const double kp = o->proportional_gain;
    if (lagged()) {
      const double df = saturated ? 0.0 : kp * (de - o->derivative_time * (dp - dq) / o->plan_area) + di;
      const double pump_row = (o->flow_per_hz * df - dp) / o->pump_lag;
      if (saturated) return {dp - dq, pump_row, 0.0};
      return {dp - dq, kp * de / o->integral_time, pump_row};
    }
    if (saturated) return {-dq, 0.0, 0.0};
    const double kappa = kp * o->derivative_time / o->plan_area;
    const double df = (kp * de + di + kappa * dq) / (1.0 + kappa * o->flow_per_hz);
    return {o->flow_per_hz * df - dq, kp * de / o->integral_time, 0.0};
  }
};

double grid_nyquist(const solver::Canal& canal) {
  double slowest = INFINITY;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const solver::Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i) {
      const double h = reach.depth(i), a = reach.area()[static_cast<std::size_t>(i)];
      const double c = reach.section().celerity(h, canal.options().gravity);
      const double u = a > 0.0 ? std::abs(reach.discharge()[static_cast<std::size_t>(i)] / a) : 0.0;
      const double speed = c > u ? c - u : c + u;  // the slower wave (subcritical) or the faster
      if (speed > 0.0) slowest = std::min(slowest, speed / reach.cell_length());
    }
  }
  return M_PI * slowest;
}

// The canal at its operating point and the pieces of the state-space model as they are built.
struct Assembly {
  BuiltCanal& built;
  const OutputHandle& output;
  ReservoirRows reservoir;
  int unknowns = 0;                   // canal unknowns (2 per cell)
  std::vector<double> u0, u, scale;   // steady state, work copy, typical sizes
  std::vector<Eigen::Triplet<double>> triplets;  // of A
  StateSpace sys;

  static constexpr auto kKinks = solver::LimiterKinks::centred;

  solver::Canal& canal() { return built.canal; }
  double time() { return built.canal.time(); }

  // What a probe reads: the rates, the head gate's discharge, the output.
  struct Probe {
    std::vector<double> rates;
    double gate_q = 0.0, out = 0.0;
  };
  Probe evaluate() {
    Probe p;
    canal().evaluate_rates(time(), p.rates, kKinks);
    p.gate_q = canal().end_face_discharge(0, End::upstream);
    p.out = output.value();
    return p;
  }
  // Their derivatives by a central difference of `set` (called with +h, −h, then 0 to restore).
  Probe probe(const std::function<void(double)>& set, double h) {
    set(h);
    const Probe plus = evaluate();
    set(-h);
    const Probe minus = evaluate();
    set(0.0);
    Probe d;
    d.rates.resize(plus.rates.size());
    for (std::size_t k = 0; k < d.rates.size(); ++k) d.rates[k] = (plus.rates[k] - minus.rates[k]) / (2.0 * h);
    d.gate_q = (plus.gate_q - minus.gate_q) / (2.0 * h);
    d.out = (plus.out - minus.out) / (2.0 * h);
    return d;
  }

  // The reservoir rows of a column (into A) or of the input (into B when `vector`).
  void add_reservoir_rows(int column, double dq, double dv, double di, double dp, Eigen::VectorXd* vector = nullptr) {
    if (!reservoir.o) return;
    const auto rows = reservoir.rows(dq, dv, di, dp);
    for (int k = 0; k < reservoir.states(); ++k) {
      const double value = rows[static_cast<std::size_t>(k)];
      if (value == 0.0) continue;
      if (vector) (*vector)(unknowns + k) = value;
      else triplets.emplace_back(unknowns + k, column, value);
    }
  }

  void start() {
    unknowns = 2 * canal().total_cells();
    u0.resize(static_cast<std::size_t>(unknowns));
    solver::store_state(canal(), u0.data());
    u = u0;
    if (built.reservoir) {
      gates::Reservoir& tank = built.reservoir->reservoir();
      const double q = canal().reach(0).discharge().front();
      tank.start_at_steady_state(q);
      reservoir.o = &tank.options();
      const double f = q / tank.options().flow_per_hz;
      reservoir.saturated = !(f > tank.options().min_frequency && f < tank.options().max_frequency);
    }
    // Typical sizes, as the Newton solver takes them: the largest |A|, and the largest |Q| (at
    // least 1e-3 of that area per second).
    double a_scale = 1e-12, q_scale = 1e-9;
    for (int k = 0; k < unknowns; k += 2) {
      a_scale = std::max(a_scale, std::abs(u0[static_cast<std::size_t>(k)]));
      q_scale = std::max(q_scale, std::abs(u0[static_cast<std::size_t>(k + 1)]));
    }
    scale.resize(u0.size());
    for (std::size_t k = 0; k < scale.size(); k += 2) {
      scale[k] = a_scale;
      scale[k + 1] = std::max(q_scale, 1e-3 * a_scale);
    }
    const int size = unknowns + reservoir.states();
    sys.canal_unknowns = unknowns;
    sys.B = Eigen::VectorXd::Zero(size);
    sys.C = Eigen::RowVectorXd::Zero(size);
  }

  // A_UU: the scheme's band by coloured forward differences (solver/rates_jacobian.hpp).
  bool add_canal_jacobian() {
    std::vector<double> f0;
    canal().evaluate_rates(time(), f0, kKinks);
    const solver::RatesPattern pattern = solver::rates_jacobian_pattern(unknowns / 2);
    std::vector<double> values(pattern.row.size());
    int evaluations = 0;
    if (!solver::rates_jacobian(canal(), time(), u.data(), f0.data(), scale, pattern, {kJacobianStep, kKinks},
                                values.data(), &evaluations)) {
      return false;
    }
    triplets.reserve(values.size() + 64);
    for (std::size_t j = 0; j + 1 < pattern.column_start.size(); ++j) {
      for (auto k = pattern.column_start[j]; k < pattern.column_start[j + 1]; ++k) {
        const auto entry = static_cast<std::size_t>(k);
        triplets.emplace_back(static_cast<int>(pattern.row[entry]), static_cast<int>(j), values[entry]);
      }
    }
    return true;
  }

  // C, and the reservoir rows, for the canal unknowns the output or the head gate's discharge
  // read (the band of A already holds their effect on the rates).
  void add_probed_cells() {
    std::vector<int> cells = output.cells;
    if (reservoir.o) {
      for (int c : cells_around(canal(), 0, 0, 2)) cells.push_back(c);
    }
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    for (int c : cells) {
      for (int m = 0; m < 2; ++m) {
        const auto j = static_cast<std::size_t>(2 * c + m);
        const double h = kProbeStep * std::max(std::abs(u0[j]), scale[j]);
        const Probe d = probe([&](double delta) {
          u[j] = u0[j] + delta;
          solver::load_state(canal(), u.data());
        }, h);
        sys.C(static_cast<int>(j)) = d.out;
        add_reservoir_rows(static_cast<int>(j), d.gate_q, 0.0, 0.0, 0.0);
      }
    }
  }

  // The reservoir's columns: its volume changes the head gate's flux (rates near the gate, the
  // output when it is the gate's discharge); its integral and a lagged pump's flow act on the reservoir rows only.
  void add_reservoir_columns() {
    if (!reservoir.o) return;
    gates::Reservoir& tank = built.reservoir->reservoir();
    const double v0 = tank.volume();
    const Probe d = probe([&](double delta) { tank.set_volume(v0 + delta); }, kProbeStep * v0);
    for (int row = 0; row < unknowns; ++row) {
      const double value = d.rates[static_cast<std::size_t>(row)];
      if (value != 0.0) triplets.emplace_back(row, unknowns, value);
    }
    sys.C(unknowns) = d.out;
    add_reservoir_rows(unknowns, d.gate_q, 1.0, 0.0, 0.0);
    if (!reservoir.saturated) add_reservoir_rows(unknowns + reservoir.integral_state(), 0.0, 0.0, 1.0, 0.0);
    if (reservoir.lagged()) add_reservoir_rows(unknowns + reservoir.pump_state(), 0.0, 0.0, 0.0, 1.0);
  }

  // B and D.
  void add_input(const InputHandle& input) {
    const double operating = input.value;
    const Probe d = probe([&](double delta) { input.set(operating + delta); }, kProbeStep * input.scale);
    for (int row = 0; row < unknowns; ++row) sys.B(row) = d.rates[static_cast<std::size_t>(row)];
    sys.D = d.out;
    add_reservoir_rows(-1, d.gate_q, 0.0, 0.0, 0.0, &sys.B);
  }

  void finish() {
    // Explicit (possibly zero) diagonal entries: the frequency sweep writes iω − A_ii there.
    const auto size = static_cast<int>(sys.B.size());
    for (int k = 0; k < size; ++k) triplets.emplace_back(k, k, 0.0);
    sys.A.resize(size, size);
    sys.A.setFromTriplets(triplets.begin(), triplets.end());
    sys.A.makeCompressed();
    sys.nyquist = grid_nyquist(canal());
  }
};

}  // namespace

StateSpace linearize_system(const scenarios::Scenario& s, const scenarios::ExperimentSpec& experiment,
                            const InputChoice& input_choice, const OutputChoice& output_choice, std::string* note) {
  // The operating point: the experiment's command held at its operating opening, before events.
  scenarios::ExperimentSpec e = experiment;
  e.input.kind = scenarios::InputKind::constant;
  e.events.clear();
  BuiltCanal b = scenarios::build_canal(s, e);
  b.canal.set_time(0.0);
  b.controlled->reset(0.0, b.controlled->command(0.0));
  const scenarios::SensorSpec sensors = e.sensors.value_or(s.sensors);
  const InputHandle input = find_input(b, s, input_choice);
  const OutputHandle output = find_output(b, s, sensors, output_choice);

  // As an experiment starts: a Newton stalled at minmod's kinks on a fine grid is accepted when
  // as settled as time marching would get it (docs/numerics.md).
  const solver::SteadyStateOptions steady = scenarios::initial_steady_state_options(s, e);
  const solver::SteadyStateSummary summary = solver::solve_steady_state(b.canal, steady);
  if (!summary.status) {
    throw InputError(s.source + ": experiment '" + e.name + "': no steady state at the operating point (" +
                     summary.status.message() + ")");
  }
  if (note) {
    *note = "steady state (Newton, " + std::to_string(summary.iterations) + " iterations" +
            (summary.stalled ? "; " + summary.stall : "") + ")";
  }
  b.canal.set_time(0.0);

  Assembly assembly{b, output, {}, 0, {}, {}, {}, {}, {}};
  assembly.start();
  if (!assembly.add_canal_jacobian()) {
    throw InputError(s.source + ": experiment '" + e.name +
                     "': the scheme cannot be evaluated next to the steady state (dry or non-finite cells)");
  }
  assembly.add_probed_cells();
  assembly.add_reservoir_columns();
  assembly.add_input(input);
  assembly.finish();
  assembly.sys.output_delay_s = output.level ? sensors.delay_s : 0.0;
  return assembly.sys;
}

}  // namespace canalsim::linearize
