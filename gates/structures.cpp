#include "gates/structures.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace canalsim::gates {

using solver::End;
using solver::Flux;
using solver::InteriorState;
using solver::Section;

// --- gate operation --------------------------------------------------------------------------

GateOperation::GateOperation(double opening, double max_opening)
    : command_([opening](double) { return opening; }), max_opening_(max_opening),
      position_(std::clamp(opening, 0.0, max_opening)) {}

GateOperation::GateOperation(TimeSignal command, double speed, double max_opening,
                             double initial_opening)
    : command_(std::move(command)), speed_(speed), max_opening_(max_opening),
      position_(std::clamp(initial_opening, 0.0, max_opening)) {}

double GateOperation::command(double t) const {
  return std::clamp(command_(t), 0.0, max_opening_);
}

double GateOperation::opening(double t) const {
  if (speed_ <= 0.0) return command(t);
  // Paper eq. (16): constant speed towards the command held since the last accepted step,
  // stopping on it.
  const double target = command(time_);
  const double reach = speed_ * std::max(t - time_, 0.0);
  return position_ + std::clamp(target - position_, -reach, reach);
}

void GateOperation::on_step_accepted(double t, double dt) {
  position_ = opening(t + dt);
  time_ = t + dt;
}

void GateOperation::reset(double t, double opening) {
  position_ = std::clamp(opening, 0.0, max_opening_);
  time_ = t;
}

// --- supplies -----------------------------------------------------------------------------------

SeriesLevelSupply::SeriesLevelSupply(std::vector<double> time, std::vector<double> level)
    : time_(std::move(time)), level_(std::move(level)) {
  if (time_.empty() || time_.size() != level_.size()) {
    throw std::invalid_argument("SeriesLevelSupply: time and level must be non-empty and equally long");
  }
}

double SeriesLevelSupply::level(double t) const {
  if (t <= time_.front()) return level_.front();
  if (t >= time_.back()) return level_.back();
  const auto it = std::upper_bound(time_.begin(), time_.end(), t);
  const std::size_t i = static_cast<std::size_t>(it - time_.begin());
  const double w = (t - time_[i - 1]) / (time_[i] - time_[i - 1]);
  return level_[i - 1] + w * (level_[i] - level_[i - 1]);
}

void ReservoirSupply::on_step_accepted(double, double dt, double outflow) {
  if (dt > 0.0) reservoir_.advance(dt, outflow);
}

// --- face solves --------------------------------------------------------------------------------

namespace coupling {
namespace {

// Discharge the outgoing invariant w allows at face depth h, and its derivative T (u_b ± c_b).
struct Allowed {
  double q;
  double dq_dh;
  double velocity;
  double celerity;
};

Allowed allowed_discharge(const Section& s, double g, End end, double w, double h) {
  const double a = s.area(h);
  const double phi = s.characteristic_integral(h, g);
  const double u = end == End::downstream ? w - phi : w + phi;
  const double c = s.celerity(h, g);
  const double t = s.top_width(h);
  return {a * u, t * (end == End::downstream ? u - c : u + c), u, c};
}

// Depth where the face is critical towards the outside, u_b = ±c_b: the end of the subcritical
// branch. Rectangle: Φ = 2c, so w ∓ 2c = ±c gives c = |w|/3.
double branch_depth(const Section& s, double g, End end, double w) {
  const bool towards = end == End::downstream ? w > 0.0 : w < 0.0;
  if (!towards) return 0.0;
  if (s.is_rectangular()) {
    const double c = std::abs(w) / 3.0;
    return c * c / g;
  }
  auto excess = [&](double h) {  // > 0 while supercritical towards the outside
    const Allowed a = allowed_discharge(s, g, end, w, h);
    return end == End::downstream ? a.velocity - a.celerity : -a.velocity - a.celerity;
  };
  double lo = 0.0, hi = 1e-3;
  while (excess(hi) > 0.0 && hi < 1e4) hi *= 2.0;
  for (int it = 0; it < 100 && hi - lo > 1e-14 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (excess(mid) > 0.0 ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace

// Newton from a warm start: the common case (the face state moves little between stages) takes
// one or two law evaluations. Returns nullopt when Newton leaves the subcritical branch or does
// not converge quickly; the caller then uses the bracketed solve. A step is the last when it is
// below 1e-13 h, or below 1e-8 h after a step it squared (|Δ_k| <= 10 Δ_{k-1}² / h): convergence
// is then quadratic and the error left after it is ~Δ_k²/h <= 1e-16 h, one more evaluation would
// only confirm it.
template <class Residual, class Subcritical>
std::optional<double> newton_from_guess(const Residual& residual, const Subcritical& subcritical, double guess) {
  if (!(guess > 0.0) || !subcritical(guess)) return std::nullopt;
  double h = guess;
  double previous_step = INFINITY;
  for (int it = 0; it < 8; ++it) {
    double slope = 0.0;
    const double r = residual(h, &slope);
    if (!(slope > 0.0)) return std::nullopt;
    const double next = h - r / slope;
    if (!(next > 0.0) || !subcritical(next)) return std::nullopt;
    const double step = std::abs(next - h);
    if (step <= 1e-13 * h) return next;
    if (step <= 1e-8 * h && step * h <= 10.0 * previous_step * previous_step) return next;
    previous_step = step;
    h = next;
  }
  return std::nullopt;
}

std::optional<double> solve_face_depth(const Section& section, double gravity, End end,
                                       const InteriorState& cell,
                                       const std::function<LawValue(double)>& discharge_law,
                                       double guess) {
  const double w = solver::outgoing_invariant(section, gravity, end, cell);
  // R(h) = allowed(h) - law(h) is monotone on the subcritical branch: increasing at the upstream
  // end (allowed grows with h, the law falls as the tailwater rises), decreasing downstream.
  const double sign = end == End::upstream ? 1.0 : -1.0;
  // A plain lambda, not a std::function: this runs four times per time step.
  const auto residual = [&](double h, double* slope) {
    const Allowed a = allowed_discharge(section, gravity, end, w, h);
    const LawValue l = discharge_law(h);
    if (slope) *slope = sign * (a.dq_dh - l.dq_dh);
    return sign * (a.q - l.q);
  };
  // Above the branch depth (h > branch_depth) the face is subcritical towards the outside. For a
  // rectangle that depth is closed-form; otherwise testing the speeds directly spares the warm
  // start the bisection for it.
  const double rectangular_branch = section.is_rectangular() ? branch_depth(section, gravity, end, w) : -1.0;
  const auto subcritical = [&](double h) {
    if (rectangular_branch >= 0.0) return h > rectangular_branch;
    const Allowed a = allowed_discharge(section, gravity, end, w, h);
    return (end == End::downstream ? a.velocity - a.celerity : -a.velocity - a.celerity) <= 0.0;
  };
  if (const auto quick = newton_from_guess(residual, subcritical, guess)) return quick;
  double lo = branch_depth(section, gravity, end, w);
  if (residual(lo, nullptr) > 0.0) return std::nullopt;  // choked: no subcritical face state
  double hi = std::max({2.0 * lo, 2.0 * cell.depth, 1e-4});
  while (residual(hi, nullptr) < 0.0) {
    lo = hi;
    hi *= 2.0;
    if (hi > 1e5) return std::nullopt;
  }
  double h = (guess > lo && guess < hi) ? guess : std::clamp(cell.depth, lo, hi);
  if (!(h > lo && h < hi)) h = 0.5 * (lo + hi);
  for (int it = 0; it < 100; ++it) {
    double slope = 0.0;
    const double r = residual(h, &slope);
    if (r == 0.0) return h;
    (r < 0.0 ? lo : hi) = h;
    double next = slope > 0.0 ? h - r / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);  // safeguard: bisect
    if (std::abs(next - h) <= 1e-14 * h || hi - lo <= 1e-14 * hi) return next;
    h = next;
  }
  return h;
}

double jet_depth(const Section& section, double gravity, double discharge, double energy) {
  const double q = std::abs(discharge);
  if (q == 0.0) return 0.0;
  if (section.is_rectangular()) {
    // E = h + k / h², k = Q² / (2 g b²): the cubic h³ − E h² + k = 0 has three real roots when
    // k <= 4 E³ / 27 (enough energy to pass Q). By the trigonometric solution they are
    // h_j = E/3 (1 + 2 cos(θ/3 − 2πj/3)), cos θ = 1 − 27k/(2E³): j = 0 subcritical, j = 1 the
    // supercritical jet, j = 2 negative.
    const double b = section.bottom_width;
    const double k = q * q / (2.0 * gravity * b * b);
    const double e3 = energy * energy * energy;
    if (!(energy > 0.0) || 27.0 * k >= 4.0 * e3) return section.critical_depth(q, gravity);
    const double theta = std::acos(1.0 - 13.5 * k / e3);
    constexpr double two_pi_over_3 = 2.0943951023931957;
    const double root = energy / 3.0 * (1.0 + 2.0 * std::cos(theta / 3.0 - two_pi_over_3));
    return root;
  }
  const double hc = section.critical_depth(q, gravity);
  auto specific_energy = [&](double h) {
    const double a = section.area(h);
    return h + q * q / (2.0 * gravity * a * a);
  };
  if (specific_energy(hc) >= energy) return hc;  // not enough energy for a jet: critical
  double lo = 0.0, hi = hc;  // E(h) falls from +inf to E_c on (0, h_c)
  for (int it = 0; it < 80 && hi - lo > 1e-13 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (specific_energy(mid) > energy ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace coupling

namespace {

// Critical outflow through an end face on the outgoing invariant (a choked structure).
Flux critical_face_flux(const Section& s, double g, End end, const InteriorState& cell) {
  const double w = solver::outgoing_invariant(s, g, end, cell);
  double lo = 0.0, hi = std::max(cell.depth, 1e-6) * 4.0;
  auto excess = [&](double h) {
    const double phi = s.characteristic_integral(h, g);
    const double u = end == End::downstream ? w - phi : w + phi;
    return std::abs(u) - s.celerity(h, g);
  };
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (excess(mid) > 0.0 ? lo : hi) = mid;
  }
  const double h = hi;
  const double phi = s.characteristic_integral(h, g);
  const double u = end == End::downstream ? w - phi : w + phi;
  Flux f = solver::face_state_flux(s, g, h, s.area(h) * u);
  f.max_speed = std::abs(u) + s.celerity(h, g);
  return f;
}

Flux face_flux_with_speed(const Section& s, double g, double h, double q) {
  Flux f = solver::face_state_flux(s, g, h, q);
  const double a = s.area(h);
  f.max_speed = (a > 0.0 ? std::abs(q / a) : 0.0) + s.celerity(h, g);
  return f;
}

// Momentum flux of the contracted jet a gate issues with discharge q and upstream energy E, if it
// exceeds the face's: the jet enters the pool only where it can push the jump away from the
// gate (max keeps the flux continuous across the regime border).
void add_jet(Flux& f, const Section& s, double g, double q, double energy) {
  if (q <= 0.0 || energy <= 0.0) return;
  const double hj = coupling::jet_depth(s, g, q, energy);
  if (hj <= 0.0) return;
  const double aj = s.area(hj);
  const double momentum_jet = q * q / aj + g * s.pressure_integral(hj);
  if (momentum_jet > f.momentum) {
    f.momentum = momentum_jet;
    f.max_speed = std::max(f.max_speed, q / aj + s.celerity(hj, g));
  }
}

}  // namespace

namespace {

// The depth of a gate's face where its law (the face law, the other side and the opening fixed)
// passes what the cell's outgoing characteristic allows, warm-started from and then updating
// `warm_depth`; none when the face is choked. The lambda captures one pointer, so its
// std::function needs no allocation.
std::optional<double> gate_face_depth(FaceLaw& face_law, const solver::BoundaryInput& in, End end, double& warm_depth) {
  auto law = [p = &face_law](double h) {
    const FaceLaw::Value v = (*p)(h);
    return coupling::LawValue{v.q, v.dq_dh};
  };
  const auto h = coupling::solve_face_depth(in.section, in.gravity, end, in.cell, law, warm_depth);
  if (h) warm_depth = *h;
  return h;
}

}  // namespace

// --- head gate -----------------------------------------------------------------------------------

HeadGateBoundary::HeadGateBoundary(const GateGeometry& geometry, std::shared_ptr<Supply> supply,
                                   std::shared_ptr<GateOperation> operation)
    : law_(geometry.law), width_(geometry.width), supply_(std::move(supply)),
      operation_(std::move(operation)) {}

Flux HeadGateBoundary::flux(const solver::BoundaryInput& in) const {
  const double y1 = supply_->level(in.time);
  const double a = operation_->opening(in.time);
  // The supply level and the opening are fixed during the solve (FaceLaw keeps the free
  // discharge).
  FaceLaw face_law(law_, width_, false, y1, a);
  const auto h = gate_face_depth(face_law, in, End::upstream, warm_depth_);
  if (!h) return critical_face_flux(in.section, in.gravity, End::upstream, in.cell);
  const double q = face_law.discharge_at(*h);
  Flux f = face_flux_with_speed(in.section, in.gravity, *h, q);
  add_jet(f, in.section, in.gravity, q, y1);
  return f;
}

void HeadGateBoundary::on_step_accepted(double t, double dt, double face_discharge) {
  last_discharge_ = face_discharge;
  supply_->on_step_accepted(t, dt, face_discharge);
  operation_->on_step_accepted(t, dt);
}

// --- tail gate -----------------------------------------------------------------------------------

TailGateBoundary::TailGateBoundary(const GateGeometry& geometry, TimeSignal tail_level,
                                   std::shared_ptr<GateOperation> operation)
    : law_(geometry.law), width_(geometry.width), tail_level_(std::move(tail_level)),
      operation_(std::move(operation)) {}

Flux TailGateBoundary::flux(const solver::BoundaryInput& in) const {
  const double y3 = tail_level_(in.time);
  const double a = operation_->opening(in.time);
  // Tail level and opening fixed during the solve (FaceLaw keeps the regime border).
  FaceLaw face_law(law_, width_, true, y3, a);
  const auto h = gate_face_depth(face_law, in, End::downstream, warm_depth_);
  if (!h) return critical_face_flux(in.section, in.gravity, End::downstream, in.cell);
  const double q = face_law.discharge_at(*h);
  return face_flux_with_speed(in.section, in.gravity, *h, q);
}

void TailGateBoundary::on_step_accepted(double t, double dt, double face_discharge) {
  last_discharge_ = face_discharge;
  operation_->on_step_accepted(t, dt);
}

// --- gate between pools ------------------------------------------------------------------------

GateLink::GateLink(const GateGeometry& geometry, std::shared_ptr<GateOperation> operation)
    : law_(geometry.law), width_(geometry.width), operation_(std::move(operation)) {}

solver::LinkFlux GateLink::flux(const solver::LinkInput& in) const {
  const double a = operation_->opening(in.time);
  const double g = in.gravity;
  const double sill = std::max(in.upstream_cell.bed, in.downstream_cell.bed);
  auto constant = [](double q) {
    return [q](double) { return coupling::LawValue{q, 0.0}; };
  };
  // Face depths that the two outgoing invariants allow for a trial discharge Q, warm-started from
  // the previous trial's (the bisection moves Q a little at a time).
  auto depths = [&](double q, double* hu, double* hd) {
    const auto up = coupling::solve_face_depth(in.upstream_section, g, End::downstream,
                                               in.upstream_cell, constant(q), *hu);
    const auto dn = coupling::solve_face_depth(in.downstream_section, g, End::upstream,
                                               in.downstream_cell, constant(q), *hd);
    if (!up || !dn) return false;
    *hu = *up;
    *hd = *dn;
    return true;
  };
  // G(Q) = Q − gate(h_u(Q), h_d(Q)) increases with Q: h_u falls and h_d rises as Q grows.
  auto gap = [&](double q, double* hu, double* hd, bool* valued) {
    *valued = depths(q, hu, hd);
    if (!*valued) return q > 0.0 ? 1.0 : -1.0;
    const double y1 = in.upstream_cell.bed + *hu - sill;
    const double y3 = in.downstream_cell.bed + *hd - sill;
    return q - width_ * law_.discharge(std::max(y1, 0.0), std::max(y3, 0.0), a);
  };
  double hu = in.upstream_cell.depth, hd = in.downstream_cell.depth;
  const double scale = width_ * critical_discharge(std::max({hu, hd, 1e-6}), g) * 2.0 + 1e-12;
  // Root of G on [−scale, scale]: bisection until both bracket ends have a face state (G is then
  // a value, not just a sign), then the Illinois variant of regula falsi (Dowell & Jarratt 1971),
  // which keeps the bracket and converges superlinearly — a dozen trials instead of ~45.
  double lo = -scale, hi = scale, g_lo = 0.0, g_hi = 0.0;
  bool lo_valued = false, hi_valued = false;
  int kept = 0;  // which end the last trial replaced: −1 lo, +1 hi
  double q = 0.0;
  for (int it = 0; it < 200 && hi - lo > 1e-13 * scale; ++it) {
    q = lo_valued && hi_valued ? lo - g_lo * (hi - lo) / (g_hi - g_lo) : 0.5 * (lo + hi);
    if (!(q > lo && q < hi)) q = 0.5 * (lo + hi);
    bool valued = false;
    const double gq = gap(q, &hu, &hd, &valued);
    if (gq == 0.0) {
      lo = hi = q;
      break;
    }
    if (gq < 0.0) {
      lo = q, g_lo = gq, lo_valued = valued;
      if (kept == -1 && hi_valued) g_hi *= 0.5;  // Illinois: halve the stale end's value
      kept = -1;
    } else {
      hi = q, g_hi = gq, hi_valued = valued;
      if (kept == 1 && lo_valued) g_lo *= 0.5;
      kept = 1;
    }
    if (std::abs(gq) <= 1e-14 * scale) {
      lo = hi = q;
      break;
    }
  }
  q = 0.5 * (lo + hi);
  if (!depths(q, &hu, &hd)) {
    hu = in.upstream_cell.depth;
    hd = in.downstream_cell.depth;
  }
  const Flux fu = face_flux_with_speed(in.upstream_section, g, hu, q);
  Flux fd = face_flux_with_speed(in.downstream_section, g, hd, q);
  add_jet(fd, in.downstream_section, g, q, in.upstream_cell.bed + hu - sill);
  solver::LinkFlux out;
  out.mass = q;
  out.momentum_upstream = fu.momentum;
  out.momentum_downstream = fd.momentum;
  out.max_speed = std::max(fu.max_speed, fd.max_speed);
  return out;
}

void GateLink::on_step_accepted(double t, double dt, double face_discharge) {
  last_discharge_ = face_discharge;
  operation_->on_step_accepted(t, dt);
}

// --- weir ------------------------------------------------------------------------------------------

WeirBoundary::WeirBoundary(double crest_height, double coefficient, double width)
    : crest_(crest_height), coefficient_(coefficient), width_(width) {}

Flux WeirBoundary::flux(const solver::BoundaryInput& in) const {
  auto law = [&](double h) {
    const double head = std::max(h - crest_, 0.0);
    return coupling::LawValue{coefficient_ * width_ * head * std::sqrt(head),
                              1.5 * coefficient_ * width_ * std::sqrt(head)};
  };
  const auto h = coupling::solve_face_depth(in.section, in.gravity, End::downstream, in.cell, law, -1.0);
  if (!h) return critical_face_flux(in.section, in.gravity, End::downstream, in.cell);
  return face_flux_with_speed(in.section, in.gravity, *h, law(*h).q);
}

// --- pump ------------------------------------------------------------------------------------------

PumpBoundary::PumpBoundary(double discharge, double stop_depth)
    : discharge_(discharge), stop_depth_(stop_depth) {}

Flux PumpBoundary::flux(const solver::BoundaryInput& in) const {
  auto law = [&](double h) {
    const bool throttled = h < stop_depth_;
    return coupling::LawValue{discharge_ * (throttled ? std::max(h, 0.0) / stop_depth_ : 1.0),
                              throttled && h > 0.0 ? discharge_ / stop_depth_ : 0.0};
  };
  const auto h = coupling::solve_face_depth(in.section, in.gravity, End::downstream, in.cell, law, -1.0);
  if (!h) return critical_face_flux(in.section, in.gravity, End::downstream, in.cell);
  return face_flux_with_speed(in.section, in.gravity, *h, law(*h).q);
}

void PumpBoundary::on_step_accepted(double, double, double face_discharge) { last_discharge_ = face_discharge; }

}  // namespace canalsim::gates
