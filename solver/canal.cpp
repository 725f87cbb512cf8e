#include "solver/canal.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "solver/scheme.hpp"

namespace canalsim::solver {
namespace {

const char* end_name(End end) { return end == End::upstream ? "upstream" : "downstream"; }

}  // namespace

double VolumeBalance::relative_error() const {
  const double scale = std::max({std::abs(initial_storage), std::abs(storage), std::abs(inflow),
                                 std::abs(outflow), std::abs(lateral), 1e-300});
  return std::abs(error()) / scale;
}

Canal::Canal(SolverOptions options) : options_(options), options_status_(validate(options)) {}

Status Canal::add_reach(const ReachSpec& spec) {
  if (!options_status_) return options_status_;
  if (auto st = validate(spec); !st) return st;
  reaches_.emplace_back(spec);
  upstream_ends_.emplace_back();
  downstream_ends_.emplace_back();
  Accumulators acc;
  acc.initial_storage = reaches_.back().volume();
  acc_.push_back(acc);
  return Status::ok();
}

Status Canal::set_boundary(int r, End end, std::shared_ptr<Boundary> boundary) {
  if (r < 0 || r >= reach_count()) return Status::error("set_boundary: reach index " + std::to_string(r) + " does not exist");
  if (!boundary) return Status::error("set_boundary: boundary is null");
  EndConnection& c = (end == End::upstream ? upstream_ends_ : downstream_ends_)[static_cast<std::size_t>(r)];
  if (c.link) return Status::error(std::string("set_boundary: the ") + end_name(end) + " end of reach " + std::to_string(r) + " already has a link");
  c.boundary = std::move(boundary);
  return Status::ok();
}

Status Canal::connect(int up, int down, std::shared_ptr<Link> link) {
  if (up < 0 || up >= reach_count() || down < 0 || down >= reach_count() || up == down)
    return Status::error("connect: reaches " + std::to_string(up) + " and " + std::to_string(down) + " must be two different existing reaches");
  if (!link) return Status::error("connect: link is null");
  auto& a = downstream_ends_[static_cast<std::size_t>(up)];
  auto& b = upstream_ends_[static_cast<std::size_t>(down)];
  if (a.boundary || a.link || b.boundary || b.link)
    return Status::error("connect: an end of reach " + std::to_string(up) + " or " + std::to_string(down) + " is already closed");
  a.link = link;
  a.other_reach = down;
  b.link = std::move(link);
  b.other_reach = up;
  return Status::ok();
}

Status Canal::check_ready() const {
  if (!options_status_) return options_status_;
  if (reaches_.empty()) return Status::error("the canal has no reach");
  for (int r = 0; r < reach_count(); ++r) {
    for (End end : {End::upstream, End::downstream}) {
      const auto& c = (end == End::upstream ? upstream_ends_ : downstream_ends_)[static_cast<std::size_t>(r)];
      if (!c.boundary && !c.link)
        return Status::error(std::string("the ") + end_name(end) + " end of reach " + std::to_string(r) + " (" + reach(r).name() + ") has no boundary or link");
    }
    const Reach& R = reach(r);
    for (int i = 0; i < R.cells(); ++i) {
      const double a = R.area()[static_cast<std::size_t>(i)], q = R.discharge()[static_cast<std::size_t>(i)];
      if (!std::isfinite(a) || !std::isfinite(q) || a < 0.0 || !std::isfinite(R.lateral_inflow()[static_cast<std::size_t>(i)]))
        return Status::error_at("state is non-finite or has a negative area (allowed: finite A >= 0, finite Q and q_l)", time_, r, i);
    }
  }
  return Status::ok();
}

void Canal::save_start_state() {
  for (Reach& r : reaches_) {
    std::copy(r.area_.begin(), r.area_.end(), r.area0_.begin());
    std::copy(r.discharge_.begin(), r.discharge_.end(), r.discharge0_.begin());
  }
}

void Canal::restore_start_state() {
  for (Reach& r : reaches_) {
    std::copy(r.area0_.begin(), r.area0_.end(), r.area_.begin());
    std::copy(r.discharge0_.begin(), r.discharge0_.end(), r.discharge_.begin());
  }
}

double Canal::compute_fluxes(double t, bool centred_kinks) {
  const double g = options_.gravity;
  const StageSettings settings{options_.order == SpatialOrder::second,
                               options_.limiter == Limiter::van_leer, options_.limiter_theta,
                               options_.dry_depth, centred_kinks};
  double limit = std::numeric_limits<double>::infinity();
  // Interior faces of every reach first: the end faces need the primitives of neighbours.
  for (Reach& r : reaches_) {
    const double smax = compute_interior_fluxes(r, settings, g);
    if (smax > 0.0) limit = std::min(limit, r.dx_ / smax);
    if (!r.outlets_.empty()) r.update_outlets();  // level-dependent withdrawals of this stage
  }
  // The interior state extrapolated to an end face (the MUSCL face value; the cell average at
  // first order), so that the boundary sees the same depth as the cell's own reconstruction.
  auto interior = [&](const Reach& r, int i) {
    const auto j = static_cast<std::size_t>(i);
    const double half = i == 0 ? -0.5 : 0.5;
    const double h = r.h_[j] + half * r.dh_[j];
    const double eta = r.eta_[j] + half * r.deta_[j];
    const double a = r.section_.area(h);
    const double u = h > options_.dry_depth ? r.u_[j] + half * r.du_[j] : 0.0;
    return InteriorState{a, a * u, h, eta - h};
  };
  for (std::size_t ri = 0; ri < reaches_.size(); ++ri) {
    Reach& r = reaches_[ri];
    const auto n = static_cast<std::size_t>(r.cells_);
    double speed = 0.0;
    if (const auto& c = upstream_ends_[ri]; c.boundary) {
      const Flux f = c.boundary->flux({End::upstream, interior(r, 0), r.section_, g, t, r.dx_});
      r.face_mass_[0] = f.mass;
      r.face_momentum_right_[0] = f.momentum;
      speed = std::max(speed, f.max_speed);
    }
    // An offtake at the end face (Reach::fixed_end_withdrawal): the structure sees the flow that
    // goes on past it, the reach's face passes the structure's flux plus the withdrawal.
    const InteriorState end_cell = interior(r, r.cells_ - 1);
    const double withdrawn = r.evaluate_end_withdrawal(end_cell.depth, options_.dry_depth);
    InteriorState beyond = end_cell;
    beyond.discharge -= withdrawn;
    // Level continuous across the offtake: the reach side's momentum flux is that of the face
    // state carrying Q_b + Q_w instead of Q_b, i.e. + ((Q_b + Q_w)² − Q_b²) / A.
    auto with_offtake = [&](double mass, double momentum) {
      r.face_mass_[n] = mass + withdrawn;
      r.face_momentum_left_[n] =
          withdrawn != 0.0 && end_cell.area > 0.0 ? momentum + withdrawn * (2.0 * mass + withdrawn) / end_cell.area
                                                  : momentum;
    };
    if (const auto& c = downstream_ends_[ri]; c.boundary) {
      const Flux f = c.boundary->flux({End::downstream, beyond, r.section_, g, t, r.dx_});
      with_offtake(f.mass, f.momentum);
      speed = std::max(speed, f.max_speed);
    } else if (c.link) {
      Reach& d = reaches_[static_cast<std::size_t>(c.other_reach)];
      LinkInput in{beyond, interior(d, 0), r.section_, d.section_, g, t};
      const LinkFlux f = c.link->flux(in);
      with_offtake(f.mass, f.momentum_upstream);
      d.face_mass_[0] = f.mass;
      d.face_momentum_right_[0] = f.momentum_downstream;
      if (f.max_speed > 0.0) limit = std::min(limit, std::min(r.dx_, d.dx_) / f.max_speed);
    }
    if (speed > 0.0) limit = std::min(limit, r.dx_ / speed);
  }
  return limit;
}

Status Canal::apply_update(double dt, double alpha, double weight, bool final_stage, bool* reject) {
  const double g = options_.gravity;
  for (std::size_t ri = 0; ri < reaches_.size(); ++ri) {
    Reach& r = reaches_[ri];
    const UpdateSettings settings{dt, alpha, options_.dry_depth, g * r.manning_n_ * r.manning_n_};
    const UpdateResult res = apply_stage_update(r, settings, g);
    if (res.any_non_finite) return find_non_finite(time_ + dt);
    Accumulators& acc = acc_[ri];
    acc.stage_inflow += weight * dt * r.face_mass_[0];
    // An end-face offtake is lateral outflow, not flow through the end (nor through a link).
    acc.stage_outflow += weight * dt * (r.face_mass_[static_cast<std::size_t>(r.cells_)] - r.stage_end_withdrawal_);
    if (res.any_lateral) acc.stage_lateral += weight * dt * lateral_volume_rate(r, options_.dry_depth);
    acc.stage_lateral -= weight * dt * r.stage_end_withdrawal_;
    if (res.any_negative) {
      // Tolerate round-off (a cell drained exactly); a real loss of positivity rejects the step.
      double scale = 0.0, min_area = 0.0;
      for (double a : r.area0_) scale = std::max(scale, a);
      for (double a : r.area_) min_area = std::min(min_area, a);
      if (min_area < -1e-12 * scale) {
        *reject = true;
        return Status::ok();
      }
      if (final_stage) {
        for (int i = 0; i < r.cells_; ++i) {
          double& a = r.area_[static_cast<std::size_t>(i)];
          if (a < 0.0) {
            acc.correction += -a * r.dx_;
            a = 0.0;
            r.discharge_[static_cast<std::size_t>(i)] = 0.0;
          }
        }
      }
    }
  }
  return Status::ok();
}

Status Canal::find_non_finite(double t) const {
  for (int r = 0; r < reach_count(); ++r) {
    const Reach& R = reach(r);
    for (int i = 0; i < R.cells(); ++i)
      if (!std::isfinite(R.area()[static_cast<std::size_t>(i)]) || !std::isfinite(R.discharge()[static_cast<std::size_t>(i)]))
        return Status::error_at("the state became non-finite", t, r, i);
  }
  return Status::error_at("the state became non-finite", t, -1, -1);
}

Status Canal::step(double max_dt) {
  if (!options_status_) return options_status_;
  if (reaches_.empty()) return Status::error("the canal has no reach");
  if (!(max_dt > 0.0)) return Status::error("step: max_dt must be positive");
  const double t = time_;
  const bool second = options_.order == SpatialOrder::second;
  save_start_state();
  const double limit = compute_fluxes(t);
  double dt = std::min({options_.cfl * limit, options_.max_time_step, max_dt});
  if (!std::isfinite(dt))
    return Status::error_at("no wave moves and no time limit was given: the time step is unbounded", t, -1, -1);
  bool clipped = dt == max_dt;
  for (int attempt = 0;; ++attempt) {
    if (attempt > 0) {
      restore_start_state();
      compute_fluxes(t);
    }
    for (auto& acc : acc_) acc.stage_inflow = acc.stage_outflow = acc.stage_lateral = 0.0;
    bool reject = false;
    Status st;
    if (!second) {
      st = apply_update(dt, 0.0, 1.0, true, &reject);
    } else {
      st = apply_update(dt, 0.0, 0.5, false, &reject);
      // Heun's second stage; a Courant number above 1 there means dt was too optimistic.
      if (st && !reject && !(dt <= compute_fluxes(t + dt))) reject = true;
      if (st && !reject) st = apply_update(dt, 0.5, 0.5, true, &reject);
    }
    if (!st) {
      restore_start_state();
      return st;
    }
    if (!reject) break;
    if (attempt >= options_.max_step_retries) {
      restore_start_state();
      std::ostringstream text;
      text << "step rejected " << attempt + 1 << " times (negative depth or Courant number > 1); last dt = " << dt << " s";
      return Status::error_at(text.str(), t, -1, -1);
    }
    dt *= 0.5;
    clipped = false;
    ++stats_.retries;
  }
  for (std::size_t ri = 0; ri < reaches_.size(); ++ri) {
    Accumulators& acc = acc_[ri];
    acc.inflow += acc.stage_inflow;
    acc.outflow += acc.stage_outflow;
    acc.lateral += acc.stage_lateral;
    if (upstream_ends_[ri].boundary) upstream_ends_[ri].boundary->on_step_accepted(t, dt, acc.stage_inflow / dt);
    if (downstream_ends_[ri].boundary) downstream_ends_[ri].boundary->on_step_accepted(t, dt, acc.stage_outflow / dt);
    if (downstream_ends_[ri].link) downstream_ends_[ri].link->on_step_accepted(t, dt, acc.stage_outflow / dt);
  }
  time_ = clipped ? t + max_dt : t + dt;
  ++stats_.steps;
  stats_.last_dt = dt;
  stats_.min_dt = std::min(stats_.min_dt, dt);
  return Status::ok();
}

Status Canal::advance_to(double t_end) {
  if (!(t_end >= time_) || !std::isfinite(t_end)) {
    std::ostringstream text;
    text << "advance_to: t_end = " << t_end << " s is outside the allowed range [" << time_ << ", inf) s";
    return Status::error(text.str());
  }
  if (auto st = check_ready(); !st) return st;
  while (time_ < t_end) {
    const double max_dt = t_end - time_;
    if (auto st = step(max_dt); !st) return st;
    // A step clipped to t_end lands on it exactly (no accumulated round-off).
    if (stats_.last_dt == max_dt || time_ > t_end) time_ = t_end;
  }
  return Status::ok();
}

double Canal::sample(int ri, double x, Quantity quantity) const {
  const Reach& r = reach(ri);
  const double g = options_.gravity;
  auto value = [&](int i) {
    const auto j = static_cast<std::size_t>(i);
    const double a = r.area()[j], h = std::max(r.section().depth(a), 0.0);
    const double u = h > options_.dry_depth ? r.discharge()[j] / a : 0.0;
    switch (quantity) {
      case Quantity::depth: return h;
      case Quantity::level: return r.bed()[j] + h;
      case Quantity::area: return a;
      case Quantity::discharge: return r.discharge()[j];
      case Quantity::velocity: return u;
      case Quantity::froude: {
        const double c = r.section().celerity(h, g);
        return c > 0.0 ? std::abs(u) / c : 0.0;
      }
    }
    return 0.0;
  };
  const double s = std::clamp(x / r.cell_length() - 0.5, 0.0, static_cast<double>(r.cells() - 1));
  const int i = std::min(static_cast<int>(s), r.cells() - 2);
  const double w = s - i;
  return (1.0 - w) * value(i) + w * value(i + 1);
}

VolumeBalance Canal::balance(int ri) const {
  const Accumulators& acc = acc_.at(static_cast<std::size_t>(ri));
  VolumeBalance b;
  b.initial_storage = acc.initial_storage;
  b.storage = reach(ri).volume();
  b.inflow = acc.inflow;
  b.outflow = acc.outflow;
  b.lateral = acc.lateral;
  b.positivity_correction = acc.correction;
  return b;
}

VolumeBalance Canal::total_balance() const {
  VolumeBalance t;
  for (int r = 0; r < reach_count(); ++r) {
    const VolumeBalance b = balance(r);
    t.initial_storage += b.initial_storage;
    t.storage += b.storage;
    t.lateral += b.lateral;
    t.positivity_correction += b.positivity_correction;
    // Only free ends count: flow through links leaves one reach and enters the next.
    if (upstream_ends_[static_cast<std::size_t>(r)].boundary) t.inflow += b.inflow;
    if (downstream_ends_[static_cast<std::size_t>(r)].boundary) t.outflow += b.outflow;
  }
  return t;
}

int Canal::total_cells() const {
  int n = 0;
  for (const Reach& r : reaches_) n += r.cells_;
  return n;
}

void Canal::evaluate_rates(double t, std::vector<double>& rates, LimiterKinks kinks) {
  compute_fluxes(t, kinks == LimiterKinks::centred);  // primitives, limited slopes, interior and end-face fluxes of every reach
  const double g = options_.gravity;
  rates.assign(2 * static_cast<std::size_t>(total_cells()), 0.0);
  std::size_t c = 0;
  for (const Reach& r : reaches_) {
    const Section& s = r.section_;
    const double friction = g * r.manning_n_ * r.manning_n_;
    for (std::size_t i = 0; i < static_cast<std::size_t>(r.cells_); ++i, ++c) {
      // The same terms as the stage update (scheme.cpp), divided by dt.
      const double hl = r.h_[i] - 0.5 * r.dh_[i], hr = r.h_[i] + 0.5 * r.dh_[i];
      const double source = g * s.mean_area(hl, hr) * (r.dh_[i] - r.deta_[i]);
      const bool wet = r.h_[i] > options_.dry_depth;
      const double qlat = wet ? r.lateral_inflow_[i] : std::max(r.lateral_inflow_[i], 0.0);
      const double a = r.area_[i], q = r.discharge_[i];
      double dq = -(r.face_momentum_left_[i + 1] - r.face_momentum_right_[i] - source) / r.dx_ +
                  std::min(qlat, 0.0) * r.u_[i];
      if (wet && friction > 0.0 && a > 0.0) {
        // The update's formula (scheme.cpp), k = g n² |Q| ρ^{4/3} / A with ρ = P/A = 1/R and the
        // same inverse cube root, so that L(U) = 0 is a fixed point of a step to round-off.
        const double rho = s.wetted_perimeter(r.h_[i]) * r.inv_area_[i];
        const double rho_m13 = inverse_cube_root_positive(rho);
        const double rho43 = rho * rho * (rho_m13 * rho_m13);
        dq -= friction * std::abs(q) * rho43 * r.inv_area_[i] * q;
      }
      rates[2 * c] = -(r.face_mass_[i + 1] - r.face_mass_[i]) / r.dx_ + qlat;
      rates[2 * c + 1] = dq;
    }
  }
}

double Canal::end_face_discharge(int ri, End end) const {
  const Reach& r = reach(ri);
  return r.face_mass_[end == End::upstream ? 0 : static_cast<std::size_t>(r.cells_)];
}

bool Canal::boundary_flux(int ri, End end, const InteriorState& cell, double t, Flux* out) const {
  if (ri < 0 || ri >= reach_count()) return false;
  const auto& c = (end == End::upstream ? upstream_ends_ : downstream_ends_)[static_cast<std::size_t>(ri)];
  if (!c.boundary) return false;
  const Reach& r = reaches_[static_cast<std::size_t>(ri)];
  *out = c.boundary->flux({end, cell, r.section_, options_.gravity, t, r.dx_});
  return true;
}

void Canal::reset_balance() {
  for (std::size_t ri = 0; ri < reaches_.size(); ++ri) {
    acc_[ri] = Accumulators{};
    acc_[ri].initial_storage = reaches_[ri].volume();
  }
}

}  // namespace canalsim::solver
