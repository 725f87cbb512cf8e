#include "scenarios/staggered.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "core/laws.hpp"
#include "scenarios/simulate.hpp"
#include "solver/illinois.hpp"

namespace canalsim::scenarios {
namespace {

constexpr double kMm = 1e-3;
constexpr double gravity = 9.81;

// ---------------------------------------------------------------------------------------------
// The gates: Swamee (1992) with this simulator's own regularisation (header), or the paper's
// eqs. 9/11; per unit width, positive from side 1 to side 3.

struct TruthGate {
  GateLaw law = GateLaw::swamee;
  double free_multiplier = 1.0, submerged_multiplier = 1.0;
  double simple_cd = 0.6;
  double leakage_m = 0.0;
  double rating_exponent = 0.0, rating_curvature = 0.0, rating_reference_m = 0.025;
  double smoothing_m = 0.0, border_margin_m = 0.0;
};

TruthGate truth_gate(const GateSpec& spec, const StaggeredOptions& o) {
  TruthGate gate;
  gate.law = spec.law;
  gate.free_multiplier = spec.discharge_coefficient;
  gate.submerged_multiplier = spec.submerged_coefficient();
  gate.leakage_m = spec.leakage_m;
  gate.rating_exponent = spec.cd_opening_exponent;
  gate.rating_curvature = spec.cd_opening_curvature;
  gate.rating_reference_m = spec.cd_reference_opening();
  gate.smoothing_m = o.zero_head_smoothing_m;
  gate.border_margin_m = o.border_margin_m;
  return gate;
}

// Swamee's free flow, q = 0.864 a √(g y1) ((y1 − a)/(y1 + 15 a))^0.072, the opening capped at
// 0.9 y1 (the law rises to its maximum near there and was not fitted beyond).
double swamee_free(double y1, double a) {
  a = std::min(a, 0.9 * y1);
  return 0.864 * a * std::sqrt(gravity * y1) * std::pow((y1 - a) / (y1 + 15.0 * a), 0.072);
}

// The submerged law's power of the head, h^0.7, smooth through zero head: h (h² + ε²)^-0.15.
double head_power(double head, double smoothing) {
  return smoothing > 0.0 ? head * std::pow(head * head + smoothing * smoothing, -0.15) : std::pow(head, 0.7);
}

double gate_discharge(const TruthGate& gate, double y1, double y3, double opening) {
  if (y3 > y1) return -gate_discharge(gate, y3, y1, opening);
  const double a = std::max(opening, 0.0) + gate.leakage_m;
  if (a <= 0.0 || y1 <= 0.0) return 0.0;
  const double x = std::clamp(std::log(a / gate.rating_reference_m), -4.0, 4.0);
  const double rating = std::exp(gate.rating_exponent * x + gate.rating_curvature * x * x);
  // Paper eq. (23), the border floored smoothly over the tail: a gate opened wider than the
  // tail's border still drowns as the head vanishes.
  const double y_lc = y3 > 0.0 ? laws::free_flow_limit_level(y3, a) : 0.0;
  const double border = y3 + std::hypot(std::max(y_lc - y3, 0.0), gate.border_margin_m);
  if (gate.law == GateLaw::simple) {
    const double cd_a = gate.simple_cd * rating * std::min(a, y1);
    if (y3 <= 0.0 || y1 >= y_lc) return gate.free_multiplier * cd_a * std::sqrt(2.0 * gravity * y1);
    return gate.submerged_multiplier * cd_a * std::sqrt(2.0 * gravity * (y1 - y3));
  }
  const double free = rating * swamee_free(y1, a);
  if (y3 <= 0.0 || y1 >= border) return gate.free_multiplier * free;
  const double h = head_power(y1 - y3, gate.smoothing_m);
  const double submergence = h / (0.32 * std::pow(border - y1, 0.7) + h);  // 1 at the border, 0 at zero head
  const double multiplier = gate.submerged_multiplier + (gate.free_multiplier - gate.submerged_multiplier) * submergence;
  return multiplier * free * submergence;
}

// ---------------------------------------------------------------------------------------------
// The canal: one rectangular pool on a staggered grid between the head gate (face 0) and the
// downstream structure (face N).

struct Reservoir {
  bool held_level = false;  // a fixed level: no pump
  double level = 0.0, area = 0.0;
  double setpoint = 0.0, kp = 0.0, ti = 1.0, td = 0.0;
  double flow_per_hz = 0.0, max_hz = 0.0, lag = 0.0;
  double integral_hz = 0.0, pump_flow = 0.0, previous_level = 0.0;

  // The controller at the start of the step (derivative on the level, integral stopped while the
  // pump saturates further), the pump's lag and the volume integrated exactly over it.
  void advance(double dt, double outflow) {
    if (held_level) return;
    const double error = setpoint - level;
    const double slope = dt > 0.0 ? (level - previous_level) / dt : 0.0;
    const double wanted = kp * (error - td * slope) + integral_hz;
    const double frequency = std::clamp(wanted, 0.0, max_hz);
    const bool pushing_out = (wanted > max_hz && error > 0.0) || (wanted < 0.0 && error < 0.0);
    if (!pushing_out) integral_hz += kp * error * dt / ti;
    const double drive = flow_per_hz * frequency;
    double delivered = drive * dt;
    if (lag > 0.0) {
      const double decay = std::exp(-dt / lag);
      delivered += (pump_flow - drive) * lag * (1.0 - decay);
      pump_flow = drive + (pump_flow - drive) * decay;
    } else {
      pump_flow = drive;
    }
    previous_level = level;
    level += (delivered - outflow * dt) / area;
  }
};

struct Downstream {
  DownstreamKind kind = DownstreamKind::closed;
  TruthGate gate;
  double opening = 0.0, tail = 0.0;
  double weir_crest = 0.0, weir_per_width = 0.0;  // C w / b

  double discharge(double depth) const {
    switch (kind) {
      case DownstreamKind::gate: return gate_discharge(gate, depth, tail, opening);
      case DownstreamKind::weir:
        return depth > weir_crest ? weir_per_width * std::pow(depth - weir_crest, 1.5) : 0.0;
      default: return 0.0;
    }
  }
};

class StaggeredPool {
 public:
  StaggeredPool(const Scenario& s, const StaggeredOptions& o)
      : cells_(o.cells), dx_(s.pools[0].length_m / o.cells), width_(s.pools[0].bottom_width_m),
        manning_(s.pools[0].manning_n), courant_(o.courant), head_(truth_gate(*s.head_gate, o)),
        depth_(cells_), velocity_(cells_ + 1, 0.0), flux_(cells_ + 1, 0.0), bed_(cells_) {
    const PoolSpec& pool = s.pools[0];
    for (int i = 0; i < cells_; ++i) bed_[i] = pool.bed_elevation_m - pool.bed_slope * (i + 0.5) * dx_;
    downstream_.kind = s.downstream.kind;
    downstream_.gate = truth_gate(s.downstream.gate, o);
    downstream_.opening = s.downstream.gate.opening_m;
    downstream_.tail = s.downstream.tail_level_m;
    downstream_.weir_crest = s.downstream.weir_crest_m;
    const double weir_width = s.downstream.weir_width_m > 0.0 ? s.downstream.weir_width_m : width_;
    downstream_.weir_per_width = s.downstream.weir_coefficient * weir_width / width_;
    const UpstreamSpec& up = s.upstream;
    reservoir_.held_level = up.kind == UpstreamKind::level;
    reservoir_.level = reservoir_.previous_level = reservoir_.setpoint = up.level_m;
    reservoir_.area = up.plan_area_m2;
    reservoir_.kp = up.pid_kp;
    reservoir_.ti = up.pid_ti_s;
    reservoir_.td = up.pid_td_s;
    reservoir_.flow_per_hz = up.pump_m3s_per_hz;
    reservoir_.max_hz = up.max_frequency_hz;
    reservoir_.lag = up.pump_lag_s;
    for (const OfftakeSpec& offtake : pool.offtakes) {
      offtakes_.push_back({std::clamp(static_cast<int>(offtake.x_m / dx_), 0, cells_ - 1), offtake});
    }
  }

  // A level pool passing what both structures pass at the opening, the pump delivering it: the
  // start of the march to the steady state.
  void start_at(double opening) {
    opening_ = opening;
    const double y_up = reservoir_.level;
    const auto imbalance = [&](double h) {
      return gate_discharge(head_, y_up, h, opening) - downstream_.discharge(h);
    };
    // The depth at which the gate passes what the downstream structure does: a level pool to
    // start from, which the settling run then brings to the steady profile.
    const double shallow = 1e-4;
    const solver::IllinoisResult root = solver::illinois(imbalance, shallow, y_up, imbalance(shallow), imbalance(y_up),
                                                         {.max_iterations = 200, .absolute_width = 1e-12, .bisect_every = 4});
    std::fill(depth_.begin(), depth_.end(), 0.5 * (root.lo + root.hi));
    const double q = gate_discharge(head_, y_up, depth_[0], opening);
    for (int j = 0; j <= cells_; ++j) {
      flux_[j] = q;
      velocity_[j] = q / depth_[std::min(j, cells_ - 1)];
    }
    reservoir_.pump_flow = q * width_;
    reservoir_.integral_hz = reservoir_.flow_per_hz > 0.0 ? q * width_ / reservoir_.flow_per_hz : 0.0;
  }

  // The largest stable step (Courant number of the options).
  double stable_step() const {
    double fastest = 0.0;
    for (int i = 0; i < cells_; ++i) {
      const double u = 0.5 * (velocity_[i] + velocity_[i + 1]);
      fastest = std::max(fastest, std::abs(u) + std::sqrt(gravity * depth_[i]));
    }
    return courant_ * dx_ / fastest;
  }

  void step(double dt, double opening) {
    opening_ = opening;
    update_velocities(dt);
    update_interior_fluxes();
    const double gate_flow = solve_head_cell(dt);
    solve_end_cell(dt);
    for (int i = 1; i < cells_ - 1; ++i) depth_[i] -= dt / dx_ * (flux_[i + 1] - flux_[i]);
    withdraw_offtakes(dt);
    for (int i = 0; i < cells_; ++i) {
      if (!(depth_[i] > 0.0)) throw std::runtime_error("staggered simulator: cell " + std::to_string(i) + " ran dry");
    }
    reservoir_.advance(dt, gate_flow * width_);
  }

  double upstream_level() const { return reservoir_.level; }
  double gate_discharge_m3s() const { return flux_[0] * width_; }
  double depth_at(double x) const {  // linear between cell centres, the end cells' depth beyond
    const double s = x / dx_ - 0.5;
    if (s <= 0.0) return depth_.front();
    if (s >= cells_ - 1) return depth_.back();
    const auto i = static_cast<int>(s);
    return depth_[i] + (s - i) * (depth_[i + 1] - depth_[i]);
  }
  double last_depth() const { return depth_.back(); }
  const std::vector<double>& depths() const { return depth_; }

 private:
  // Each offtake draws from the cell holding it, at the depth the fluxes left (a fixed
  // withdrawal, or an outlet K (h − invert)^p above its invert; scenario.hpp OfftakeSpec).
  void withdraw_offtakes(double dt) {
    for (const auto& [cell, offtake] : offtakes_) {
      double& h = depth_[static_cast<std::size_t>(cell)];
      const double head = h - offtake.invert_m;
      const double q = offtake.kind == OfftakeKind::fixed ? offtake.discharge_m3s
                       : head > 0.0                        ? offtake.coefficient * std::pow(head, offtake.exponent)
                                                           : 0.0;
      h -= dt * q / (dx_ * width_);
    }
  }

  // Momentum at the interior faces, momentum-conserving form (Stelling & Duinmeijer eq. 16): the
  // velocity carried by the upwind cell-centre discharge, less the continuity's share.
  void update_velocities(double dt) {
    std::vector<double> next(velocity_);
    for (int j = 1; j < cells_; ++j) {
      const int left = j - 1, right = j;
      const double mean_depth = 0.5 * (depth_[left] + depth_[right]);
      const double q_right = 0.5 * (flux_[j] + flux_[j + 1]);
      const double q_left = 0.5 * (flux_[j - 1] + flux_[j]);
      const double u_right = q_right > 0.0 ? velocity_[j] : velocity_[j + 1];
      const double u_left = q_left > 0.0 ? velocity_[j - 1] : velocity_[j];
      const double advection = (q_right * u_right - q_left * u_left - velocity_[j] * (q_right - q_left)) / (dx_ * mean_depth);
      const double slope = (bed_[right] + depth_[right] - bed_[left] - depth_[left]) / dx_;
      const double radius = width_ * mean_depth / (width_ + 2.0 * mean_depth);
      const double friction = gravity * manning_ * manning_ * std::abs(velocity_[j]) / std::pow(radius, 4.0 / 3.0);
      next[j] = (velocity_[j] - dt * (advection + gravity * slope)) / (1.0 + dt * friction);
    }
    velocity_.swap(next);
  }

  // Continuity's face flux: the depth upwind, extrapolated to the face with van Albada's limiter.
  void update_interior_fluxes() {
    for (int j = 1; j < cells_; ++j) {
      const bool forward = velocity_[j] >= 0.0;
      const int up = forward ? j - 1 : j, down = forward ? j : j - 1, far = forward ? j - 2 : j + 1;
      double face_depth = depth_[up];
      if (far >= 0 && far < cells_) {
        const double ahead = depth_[down] - depth_[up], behind = depth_[up] - depth_[far];
        if (ahead * behind > 0.0) face_depth += 0.5 * ahead * behind * (ahead + behind) / (ahead * ahead + behind * behind);
      }
      flux_[j] = face_depth * velocity_[j];
    }
  }

  // The head cell's new depth h with the gate's flux taken at it: h = h⁰ − Δt/Δx (q₁ − q_gate(h)).
  double solve_head_cell(double dt) {
    const double old = depth_[0], out = flux_[1], y_up = reservoir_.level;
    const auto residual = [&](double h) { return h - old - dt / dx_ * (gate_discharge(head_, y_up, h, opening_) - out); };
    depth_[0] = root(residual, old);
    flux_[0] = gate_discharge(head_, y_up, depth_[0], opening_);
    velocity_[0] = flux_[0] / depth_[0];
    return flux_[0];
  }

  // The end cell's new depth with the structure's flux taken at it.
  void solve_end_cell(double dt) {
    const int last = cells_ - 1;
    const double old = depth_[last], in = flux_[last];
    const auto residual = [&](double h) { return h - old - dt / dx_ * (in - downstream_.discharge(h)); };
    depth_[last] = root(residual, old);
    flux_[cells_] = downstream_.discharge(depth_[last]);
    velocity_[cells_] = flux_[cells_] / depth_[last];
  }

  // The residual rises with the depth (both structures pass less as the cell beside them fills
  // from their other side), so a bracket about the old depth holds one root.
  template <class F>
  static double root(F&& residual, double old) {
    double width = 1e-3, lo = std::max(old - width, 1e-7), hi = old + width;
    double f_lo = residual(lo), f_hi = residual(hi);
    for (int grow = 0; grow < 40 && f_lo > 0.0; ++grow) f_lo = residual(lo = std::max(lo - (width *= 2.0), 1e-7));
    for (int grow = 0; grow < 40 && f_hi < 0.0; ++grow) f_hi = residual(hi += (width *= 2.0));
    if (f_lo > 0.0 || f_hi < 0.0) throw std::runtime_error("staggered simulator: no depth balances a gate's flux");
    solver::IllinoisOptions o;
    o.absolute_width = 1e-14;
    o.bisect_every = 8;
    return solver::illinois(residual, lo, hi, f_lo, f_hi, o).last;
  }

  int cells_;
  double dx_, width_, manning_, courant_;
  TruthGate head_;
  Downstream downstream_;
  Reservoir reservoir_;
  double opening_ = 0.0;
  std::vector<double> depth_, velocity_, flux_, bed_;
  std::vector<std::pair<int, OfftakeSpec>> offtakes_;  // the cell holding each
};

// ---------------------------------------------------------------------------------------------
// What the simulator runs, and the run.

void require_supported(const Scenario& s, const ExperimentSpec& e, const StaggeredOptions& o) {
  const std::string where = s.source.empty() ? s.name : s.source;
  const auto refuse = [&](const std::string& what) {
    throw InputError(where + ": the staggered simulator takes " + what);
  };
  if (o.cells < 3) refuse("cells >= 3 (got " + std::to_string(o.cells) + ")");
  if (!(o.courant > 0.0 && o.courant <= 0.9)) refuse("a Courant number in (0, 0.9]");
  if (!(o.zero_head_smoothing_m >= 0.0) || !(o.border_margin_m > 0.0)) refuse("a smoothing >= 0 and a border margin > 0");
  if (s.pools.size() != 1) refuse("one pool (pools has " + std::to_string(s.pools.size()) + ")");
  const PoolSpec& pool = s.pools[0];
  if (pool.side_slope != 0.0) refuse("a rectangular pool (pools[1].side_slope = 0)");
  for (const OfftakeSpec& offtake : pool.offtakes) {
    if (offtake.kind == OfftakeKind::orifice && !(offtake.coefficient > 0.0)) {
      refuse("orifice offtakes sized beforehand (pools[1].offtakes: coefficient > 0)");
    }
  }
  if (!s.head_gate || !s.head_gate->controlled) refuse("a controlled head gate (head_gate.controlled = true)");
  if (s.upstream.kind != UpstreamKind::level && s.upstream.kind != UpstreamKind::reservoir) {
    refuse("upstream.kind = \"level\" or \"reservoir\"");
  }
  const auto kind = s.downstream.kind;
  if (kind != DownstreamKind::gate && kind != DownstreamKind::weir && kind != DownstreamKind::closed) {
    refuse("downstream.kind = \"gate\", \"weir\" or \"closed\"");
  }
  if (!e.events.empty()) refuse("no events (experiment " + e.name + ")");
  if (o.drive.use_recorded_upstream) refuse("no recorded upstream level (the drive's use_recorded_upstream)");
  const SensorSpec sensors = e.sensors.value_or(s.sensors);
  if (sensors.delay_s != 0.0) refuse("sensors.delay_s = 0");
  if (s.head_gate->actuator_speed_m_s < 0.0) refuse("head_gate.actuator_speed_m_s >= 0");
}

// Marches with the command at its operating point until no depth moves by more than a
// micrometre per minute (the reservoir's loop rings down), or throws after settle_s.
void settle(StaggeredPool& pool, double opening, double settle_s) {
  pool.start_at(opening);
  const double window = 60.0;
  for (double t = 0.0; t < settle_s; t += window) {
    const std::vector<double> before = pool.depths();
    const double level_before = pool.upstream_level();
    for (double s = 0.0; s < window;) {
      const double dt = std::min(pool.stable_step(), window - s);
      pool.step(dt, opening);
      s += dt;
    }
    double moved = std::abs(pool.upstream_level() - level_before);
    for (std::size_t i = 0; i < before.size(); ++i) moved = std::max(moved, std::abs(pool.depths()[i] - before[i]));
    if (moved < 1e-6) return;
  }
  throw std::runtime_error("staggered simulator: the canal did not settle within " + format_g(settle_s) + " s");
}

// One level sensor: the true depth through the offset, the noise and the resolution (eq. 17), mm.
struct LevelReading {
  double offset_mm, noise_mm, resolution_mm;
  std::mt19937_64* rng;
  double operator()(double depth_m) const {
    double y = depth_m / kMm + offset_mm;
    if (noise_mm > 0.0) y += std::normal_distribution<double>(0.0, noise_mm)(*rng);
    return laws::quantise(y, resolution_mm);
  }
};

}  // namespace

Recording simulate_staggered(const Scenario& s, const ExperimentSpec& e, const StaggeredOptions& o) {
  require_supported(s, e, o);
  const SensorSpec sensors = e.sensors.value_or(s.sensors);
  const SignalPtr command = command_input(e, o.drive);
  const double speed = s.head_gate->actuator_speed_m_s;
  StaggeredPool pool(s, o);
  double position = command->value(-1e-9);
  settle(pool, position, o.settle_s);

  std::mt19937_64 rng(sensors.seed);
  const auto reading = [&](double offset_mm) {
    return LevelReading{sensors.offset_mm + offset_mm, sensors.noise_std_mm, sensors.resolution_mm, &rng};
  };
  const LevelReading read_up = reading(sensors.offset_y_up_mm), read_dw = reading(sensors.offset_y_dw_mm),
                     read_dwe = reading(sensors.offset_y_dwe_mm);
  const double length = s.pools[0].length_m;
  const double dwe_x = sensors.downstream_sensor_x_m < 0.0 ? length : sensors.downstream_sensor_x_m;

  const double h = sensors.period_s;
  const auto samples = static_cast<std::size_t>(std::floor(e.duration_s / h + 1e-9)) + 1;
  std::vector<double> t_s, u_mm, x_up_mm, y_up_mm, y_dw_mm, y_dwe_mm, q_lps, regime;
  double t = -e.settle_s;
  for (std::size_t k = 0; k < samples; ++k) {
    const double sample_t = static_cast<double>(k) * h;
    // March to the sample, each step ending at the command's jumps.
    while (t < sample_t - 1e-12) {
      const std::vector<double> jumps = command->jumps(t, sample_t);
      double end = jumps.empty() ? sample_t : jumps.front();
      if (end <= t + 1e-12) end = sample_t;
      const double dt = std::min(pool.stable_step(), end - t);
      const double target = command->value(t + 0.5 * dt);
      position = speed > 0.0 ? laws::rate_limited_move(position, target, speed * dt) : target;
      pool.step(dt, position);
      t += dt;
    }
    t = sample_t;
    t_s.push_back(sample_t);
    u_mm.push_back(command->value(sample_t) / kMm);
    x_up_mm.push_back(position / kMm);
    const double y_up = pool.upstream_level(), y_dwe = pool.depth_at(dwe_x);
    y_up_mm.push_back(read_up(y_up));
    y_dw_mm.push_back(read_dw(pool.depth_at(sensors.below_gate_sensor_x_m)));
    y_dwe_mm.push_back(read_dwe(y_dwe));
    q_lps.push_back(pool.gate_discharge_m3s() / kMm);
    const bool free = y_up > laws::free_flow_limit_level(y_dwe, position);
    regime.push_back(static_cast<double>(free ? RegimeCode::free : RegimeCode::submerged));
  }

  Recording rec;
  rec.source = s.name + "/" + e.name + " (staggered)";
  rec.set_meta("scenario", s.name);
  rec.set_meta("experiment", e.name);
  rec.set_meta("operating_opening_mm", format_g(e.operating_opening_mm));
  rec.set_meta("sampling_period_s", format_g(h));
  rec.set_meta("generator", "canalsim staggered simulator (Stelling & Duinmeijer 2003) on " + std::to_string(o.cells) + " cells");
  rec.set_column(columns::time, std::move(t_s));
  rec.set_column(columns::gate_command, std::move(u_mm));
  rec.set_column(columns::gate_position, std::move(x_up_mm));
  rec.set_column(columns::upstream_level, std::move(y_up_mm));
  rec.set_column(columns::level_below_gate, std::move(y_dw_mm));
  rec.set_column(columns::level_downstream_end, std::move(y_dwe_mm));
  rec.set_column(columns::discharge, std::move(q_lps));
  rec.set_column(columns::regime, std::move(regime));
  return rec;
}

Simulator staggered_simulator(const StaggeredOptions& options) {
  return [options](const Scenario& s, const ExperimentSpec& e, const SimulateOptions& run) {
    StaggeredOptions o = options;
    o.drive = run.drive;
    return simulate_staggered(s, e, o);
  };
}

}  // namespace canalsim::scenarios
