#include "gates/sluice_gate.hpp"

#include "core/laws.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace canalsim::gates {
namespace {

// Critical flow coefficient: q_c / (sqrt(g) y1^{3/2}) = (2/3)^{3/2}.
const double critical_coefficient = std::pow(2.0 / 3.0, 1.5);

// Swamee's constants (header comment).
constexpr double swamee_free_coefficient = 0.864;
constexpr double swamee_contraction_exponent = 0.072;
constexpr double swamee_jump_ratio = 15.0;
constexpr double border_exponent = laws::regime_border_exponent;  // eq. (8), (10), (23)
constexpr double submergence_weight = 0.32;
constexpr double submergence_exponent = 0.7;

// The derivatives of h^0.7 and (y_lc - y1)^0.7 are unbounded at h = 0 and at the border. For the
// Newton solve we evaluate x^-0.3 no closer than this fraction of the upstream depth: the slope is
// then large and finite with the right sign (the discharge itself is not regularised).
constexpr double singular_floor = 1e-9;

// Openings below a picometre pass no flow. The law's 1/a terms (the log-derivative in a, the
// border's dy_lc/da = -0.72 y_lc / a) overflow to inf, and then NaN, for openings that round
// towards zero (a command of 1e-320 mm); such a gate is closed for every physical purpose: it
// would pass ~1e-12 m²/s.
constexpr double smallest_opening = 1e-12;  // m

// The submerged law's power of the head, h^p, regularised near zero head (SluiceGateOptions::
// zero_head): h (h + h0)^(p - 1), with its slope (h + h0)^(p - 2) (p h + h0). With h0 = 0 the
// caller keeps its own h^p (bit for bit the published law).
struct HeadPower {
  double value, slope;
};
HeadPower regularised_head_power(double head, double h0, double p) {
  const double base = head + h0;
  const double scale = std::pow(base, p - 2.0);
  return {head * base * scale, scale * (p * head + h0)};
}

bool in_half_open(double value, double low, double high) {  // (low, high]
  return std::isfinite(value) && value > low && value <= high;
}

// Dimensionless free-flow law f(r) = q_f / (sqrt(g) y1^{3/2}) at r = a / y1.
double free_flow_shape(const SluiceGateOptions& o, double r) {
  const double m = o.discharge_coefficient_multiplier;
  if (o.law == GateLaw::simple) return m * o.simple_discharge_coefficient * std::sqrt(2.0) * r;
  if (r <= 0.0 || r >= 1.0) return 0.0;
  return m * swamee_free_coefficient * r *
         std::pow((1.0 - r) / (1.0 + swamee_jump_ratio * r), swamee_contraction_exponent);
}

// Maximiser of the free-flow shape on (0, 1]: golden-section search for Swamee (unimodal), 1 for
// the simple law (linear in r).
double free_flow_shape_argmax(const SluiceGateOptions& o) {
  if (o.law == GateLaw::simple) return 1.0;
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 200 && hi - lo > 1e-14; ++i) {
    const double x1 = hi - ratio * (hi - lo);
    const double x2 = lo + ratio * (hi - lo);
    if (free_flow_shape(o, x1) < free_flow_shape(o, x2)) {
      lo = x1;
    } else {
      hi = x2;
    }
  }
  return 0.5 * (lo + hi);
}

// Smallest r with f(r) = critical_coefficient on (0, r_max], by bisection (f increases there).
double critical_ratio_below(const SluiceGateOptions& o, double r_max) {
  double lo = 0.0, hi = r_max;
  for (int i = 0; i < 200 && hi - lo > 1e-15; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (free_flow_shape(o, mid) < critical_coefficient) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return hi;
}

double floored_power(double x, double exponent, double floor) {
  return std::pow(std::max(x, floor), exponent);
}

}  // namespace

const char* to_string(GateLaw law) {
  switch (law) {
    case GateLaw::swamee: return "swamee";
    case GateLaw::simple: return "simple";
  }
  return "unknown";
}

const char* to_string(GateRegime regime) {
  switch (regime) {
    case GateRegime::closed: return "closed";
    case GateRegime::free: return "free";
    case GateRegime::submerged: return "submerged";
    case GateRegime::out_of_water: return "out_of_water";
  }
  return "unknown";
}

Status SluiceGateOptions::validate() const {
  const double submerged = submerged_discharge_coefficient_multiplier;
  return Validator()
      .require(law == GateLaw::swamee || law == GateLaw::simple, "law", "expected swamee or simple")
      .require(in_half_open(discharge_coefficient_multiplier, 0.0, 10.0), "discharge_coefficient_multiplier",
               discharge_coefficient_multiplier, "a value in (0, 10]")
      .require(submerged == 0.0 || in_half_open(submerged, 0.0, 10.0), "submerged_discharge_coefficient_multiplier",
               submerged, "0 (= the free one) or a value in (0, 10]")
      .require(in_half_open(simple_discharge_coefficient, 0.0, 2.0), "simple_discharge_coefficient",
               simple_discharge_coefficient, "a value in (0, 2]")
      .require(std::isfinite(leakage_opening) && leakage_opening >= 0.0 && leakage_opening <= 1.0, "leakage_opening",
               leakage_opening, "a value in [0, 1] m")
      .require(std::isfinite(zero_head) && zero_head >= 0.0 && zero_head <= 1.0, "zero_head", zero_head,
               "a value in [0, 1] m")
      .require(std::isfinite(opening_exponent) && std::abs(opening_exponent) <= 2.0, "opening_exponent",
               opening_exponent, "a value in [-2, 2]")
      .require(std::isfinite(opening_curvature) && std::abs(opening_curvature) <= 2.0, "opening_curvature",
               opening_curvature, "a value in [-2, 2]")
      .require(std::isfinite(border_floor_ratio) && border_floor_ratio > 1.0 && border_floor_ratio <= 2.0,
               "border_floor_ratio", border_floor_ratio, "a value in (1, 2]")
      .require(in_half_open(reference_opening, 0.0, 100.0), "reference_opening", reference_opening,
               "a value in (0, 100] m")
      .require(in_half_open(gravity, 0.0, 100.0), "gravity", gravity, "a value in (0, 100] m/s^2")
      .status();
}

double limit_condition_level(double y_dwe, double x_up) { return laws::free_flow_limit_level(y_dwe, x_up); }

GateRegime classify_regime(double y_up, double y_dwe, double x_up) {
  const double high = std::max(y_up, y_dwe);
  const double low = std::min(y_up, y_dwe);
  if (x_up <= 0.0 || high <= 0.0) return GateRegime::closed;
  if (x_up >= high) return GateRegime::out_of_water;
  return high > limit_condition_level(low, x_up) ? GateRegime::free : GateRegime::submerged;
}

double swamee_free_discharge(double y1, double a, double gravity) {
  if (a <= 0.0 || y1 <= a) return 0.0;
  return swamee_free_coefficient * a * std::sqrt(gravity * y1) *
         std::pow((y1 - a) / (y1 + swamee_jump_ratio * a), swamee_contraction_exponent);
}

double critical_discharge(double y1, double gravity) {
  if (y1 <= 0.0) return 0.0;
  return std::sqrt(gravity) * std::pow(2.0 / 3.0 * y1, 1.5);
}

SluiceGate::SluiceGate(const SluiceGateOptions& options) : options_(options) {
  if (const Status status = options.validate(); !status) throw std::invalid_argument("sluice gate: " + status.message());
  const double r_max = free_flow_shape_argmax(options_);
  reaches_critical_ = free_flow_shape(options_, r_max) >= critical_coefficient;
  cap_ratio_ = reaches_critical_ ? critical_ratio_below(options_, r_max) : r_max;
}

// Free-flow discharge per unit width at the opening the law sees, with partials in y1 and a.
SluiceGate::Partials SluiceGate::free_flow(double y1, double a) const {
  const double g = options_.gravity;
  const double m = options_.discharge_coefficient_multiplier;
  Partials p;
  if (a <= 0.0 || y1 <= 0.0) return p;
  if (options_.law == GateLaw::simple) {
    p.q = m * options_.simple_discharge_coefficient * a * std::sqrt(2.0 * g * y1);  // eq. (9)
    p.d_y1 = p.q / (2.0 * y1);
    p.d_a = p.q / a;
    return p;
  }
  if (a >= y1) return p;  // not reached: the cap keeps a below y1 for Swamee
  const double jump = y1 + swamee_jump_ratio * a;
  p.q = m * swamee_free_discharge(y1, a, g);
  // log-derivatives of a sqrt(y1) ((y1 - a)/(y1 + 15 a))^0.072
  p.d_y1 = p.q * (0.5 / y1 + swamee_contraction_exponent * (1.0 / (y1 - a) - 1.0 / jump));
  p.d_a = p.q * (1.0 / a - swamee_contraction_exponent * (1.0 / (y1 - a) + swamee_jump_ratio / jump));
  return p;
}

// The opening the law sees, with its partials in the raw opening a and in y1: the geometric
// opening (leakage included), frozen at cap_ratio y1 near and above the surface (header comment).
struct SluiceGate::SeenOpening {
  double a = 0.0, d_a = 0.0, d_y1 = 0.0;
  bool out_of_water = false;  // the geometric opening reaches the upstream surface
};

// The border of the flow law: Swamee's y_lc (paper eq. 23), floored at κ y3 (SluiceGateOptions::
// border_floor_ratio). Without the floor a gate opened wider than ~0.75 y3 (where y_lc < y3)
// would pass free flow right up to zero head and then jump to reverse flow; with it the flow
// submerges as the head vanishes and the discharge falls continuously to zero. The paper's regime classification
// (classify_regime) keeps the published condition.
struct SluiceGate::Border {
  double y_lc = 0.0;
  bool floored = false;  // at κ y3, where it does not depend on the opening
};

SluiceGate::SeenOpening SluiceGate::seen_opening(double y1, double a, double geometric) const {
  const double dgeometric_da = a > 0.0 ? 1.0 : 0.0;
  const double cap = cap_ratio_ * y1;
  const bool capped = geometric >= cap;
  return {capped ? cap : geometric, capped ? 0.0 : dgeometric_da, capped ? cap_ratio_ : 0.0, geometric >= y1};
}

// Free discharge Qf(y1, a) and its total partials (through the seen opening), the free-flow
// partials memoised on (y1, a_seen).
SluiceGate::Partials SluiceGate::free_discharge(double y1, const SeenOpening& seen, Memo* memo) const {
  Partials out;
  if (seen.out_of_water && !reaches_critical_) {
    out.q = critical_discharge(y1, options_.gravity);  // jump documented in the header
    out.d_y1 = 1.5 * out.q / y1;
    return out;
  }
  Partials f;
  if (memo && memo->free_y1 == y1 && memo->free_a == seen.a) {
    f.q = memo->free_q;
    f.d_y1 = memo->free_d_y1;
    f.d_a = memo->free_d_a;
  } else {
    f = free_flow(y1, seen.a);
    if (memo) {
      memo->free_y1 = y1;
      memo->free_a = seen.a;
      memo->free_q = f.q;
      memo->free_d_y1 = f.d_y1;
      memo->free_d_a = f.d_a;
    }
  }
  out.q = f.q;
  out.d_y1 = f.d_y1 + f.d_a * seen.d_y1;
  out.d_a = f.d_a * seen.d_a;
  return out;
}

// The border (struct Border), Swamee's y_lc memoised on (y3, a_seen).
SluiceGate::Border SluiceGate::flow_border(double y3, double a_seen, Memo* memo) const {
  double y_lc_swamee;
  if (memo && memo->border_y3 == y3 && memo->border_a == a_seen) {
    y_lc_swamee = memo->border;
  } else {
    y_lc_swamee = limit_condition_level(y3, a_seen);
    if (memo) {
      memo->border_y3 = y3;
      memo->border_a = a_seen;
      memo->border = y_lc_swamee;
    }
  }
  const double floor = options_.border_floor_ratio * y3;
  const bool floored = floor > y_lc_swamee;
  return {floored ? floor : y_lc_swamee, floored};
}

// The simple law's submerged discharge, eq. (11), its head's square root regularised near zero
// head when zero_head > 0.
SluiceGate::Partials SluiceGate::submerged_simple(double y1, double y3, const SeenOpening& seen) const {
  Partials out;
  const double head = y1 - y3;
  const double floor = singular_floor * y1;
  const double coefficient = options_.submerged_multiplier() * options_.simple_discharge_coefficient;
  const double h0 = options_.zero_head;
  const HeadPower power = h0 > 0.0 ? regularised_head_power(head, h0, 0.5) : HeadPower{0.0, 0.0};
  const double root = h0 > 0.0 ? std::sqrt(2.0 * options_.gravity) * power.value
                               : std::sqrt(2.0 * options_.gravity * head);
  out.q = coefficient * seen.a * root;
  const double dq_dhead = h0 > 0.0 ? coefficient * seen.a * std::sqrt(2.0 * options_.gravity) * power.slope
                                   : coefficient * seen.a * std::sqrt(2.0 * options_.gravity) * 0.5 /
                                         std::sqrt(std::max(head, floor));
  out.d_y1 = dq_dhead + coefficient * root * seen.d_y1;
  out.d_y3 = -dq_dhead;
  out.d_a = coefficient * root * seen.d_a;
  return out;
}

// Swamee's submerged discharge: the free one times the submergence factor
// F = D / (0.32 S + D), D = head^0.7, S = (y_lc - y1)^0.7, with the submerged multiplier blended in.
SluiceGate::Partials SluiceGate::submerged_swamee(double y1, double y3, const SeenOpening& seen, const Partials& free,
                                                  const Border& border) const {
  const double head = y1 - y3;
  const double floor = singular_floor * y1;
  const double y_lc = border.y_lc;
  const double margin = y_lc - y1;
  const double h0 = options_.zero_head;
  const HeadPower power = h0 > 0.0 ? regularised_head_power(head, h0, submergence_exponent) : HeadPower{0.0, 0.0};
  const double D = h0 > 0.0 ? power.value : std::pow(head, submergence_exponent);
  const double S = std::pow(margin, submergence_exponent);
  const double den = submergence_weight * S + D;
  const double F = D / den;
  const double dF_dD = submergence_weight * S / (den * den);
  const double dF_dS = -submergence_weight * D / (den * den);
  // x^-0.3 = x^0.7 / x reuses D and S (two pow fewer); below the floor the slope is floored.
  const double dD_dhead = h0 > 0.0 ? power.slope
                                   : submergence_exponent *
                                         (head > floor ? D / head : floored_power(head, submergence_exponent - 1.0, floor));
  const double dS_dmargin = submergence_exponent *
      (margin > floor ? S / margin : floored_power(margin, submergence_exponent - 1.0, floor));
  const double dylc_dy3 = border.floored ? options_.border_floor_ratio : (1.0 + border_exponent) * y_lc / y3;
  const double dylc_dseen = border.floored ? 0.0 : -border_exponent * y_lc / seen.a;

  const double dF_dy1 = dF_dD * dD_dhead + dF_dS * dS_dmargin * (dylc_dseen * seen.d_y1 - 1.0);
  const double dF_dy3 = -dF_dD * dD_dhead + dF_dS * dS_dmargin * dylc_dy3;
  const double dF_da = dF_dS * dS_dmargin * dylc_dseen * seen.d_a;

  // Submerged multiplier relative to the free one, blended in F (header): q = qf F (rho + (1 - rho) F),
  // dq/dF = qf (rho + 2 (1 - rho) F). rho = 1 leaves Swamee's law exactly as published.
  const double rho = options_.submerged_multiplier() / options_.discharge_coefficient_multiplier;
  const double blend = rho + (1.0 - rho) * F;
  const double dblend = rho + 2.0 * (1.0 - rho) * F;
  Partials out;
  out.q = free.q * F * blend;
  out.d_y1 = free.d_y1 * F * blend + free.q * dF_dy1 * dblend;
  out.d_y3 = free.q * dF_dy3 * dblend;
  out.d_a = free.d_a * F * blend + free.q * dF_da * dblend;
  return out;
}

// The law's discharge times the opening rating c(a) = exp(β x + γ x²), x = ln(a / a_ref)
// (SluiceGateOptions::opening_exponent), at the opening the law sees; dc/da = c (β + 2 γ x) / a
// inside the clamp of x, 0 beyond it.
SluiceGate::Partials SluiceGate::rated(const Partials& law, const SeenOpening& seen) const {
  constexpr double kLogOpeningClamp = 4.0;
  const double beta = options_.opening_exponent, gamma = options_.opening_curvature;
  const double raw = std::log(seen.a / options_.reference_opening);
  const double x = std::clamp(raw, -kLogOpeningClamp, kLogOpeningClamp);
  const double c = std::exp(beta * x + gamma * x * x);
  const double dc_da = raw == x ? c * (beta + 2.0 * gamma * x) / seen.a : 0.0;  // per unit seen opening
  Partials out;
  out.q = c * law.q;
  out.d_y1 = c * law.d_y1 + law.q * dc_da * seen.d_y1;
  out.d_y3 = c * law.d_y3;
  out.d_a = c * law.d_a + law.q * dc_da * seen.d_a;
  return out;
}

// Flow from side 1 (the higher one, y1 >= y3) to side 3; partials in (y1, y3, raw opening a):
// the opening the law sees, the free discharge, the border of the flow law, then free flow
// (condition 8) or the submerged law (condition 10).
SluiceGate::Partials SluiceGate::forward(double y1, double y3, double a, GateRegime& regime,
                                         Memo* memo) const {
  regime = GateRegime::closed;
  const double geometric = std::max(a, 0.0) + options_.leakage_opening;
  if (geometric < smallest_opening || y1 <= 0.0) return {};
  const SeenOpening seen = seen_opening(y1, a, geometric);
  const Partials free = free_discharge(y1, seen, memo);
  const Border border = flow_border(y3, seen.a, memo);
  const bool rating = options_.opening_exponent != 0.0 || options_.opening_curvature != 0.0;
  const auto with_rating = [&](const Partials& law) { return rating ? rated(law, seen) : law; };
  if (y1 > border.y_lc) {  // condition (8): free flow
    regime = seen.out_of_water ? GateRegime::out_of_water : GateRegime::free;
    return with_rating(free);
  }
  regime = seen.out_of_water ? GateRegime::out_of_water : GateRegime::submerged;  // condition (10)
  if (options_.law == GateLaw::simple) return with_rating(submerged_simple(y1, y3, seen));
  return with_rating(submerged_swamee(y1, y3, seen, free, border));
}

GateFlow SluiceGate::evaluate(double y1, double y3, double a) const {
  Memo none;
  return evaluate(y1, y3, a, none);
}

GateFlow SluiceGate::evaluate(double y1, double y3, double a, Memo& memo) const {
  GateFlow flow;
  flow.reverse = y3 > y1;
  if (!flow.reverse) {
    const Partials p = forward(y1, y3, a, flow.regime, &memo);
    flow.q = p.q;
    flow.dq_dy1 = p.d_y1;
    flow.dq_dy3 = p.d_y3;
    flow.dq_da = p.d_a;
    return flow;
  }
  // Reverse head: q(y1, y3, a) = -Q(y3, y1, a), so the roles of the partials swap too.
  const Partials p = forward(y3, y1, a, flow.regime, &memo);
  flow.q = -p.q;
  flow.dq_dy1 = -p.d_y3;
  flow.dq_dy3 = -p.d_y1;
  flow.dq_da = -p.d_a;
  return flow;
}

FaceLaw::Value FaceLaw::operator()(double h) {
  const GateFlow f = face_upstream_ ? law_->evaluate(h, fixed_, opening_, memo_)
                                    : law_->evaluate(fixed_, h, opening_, memo_);
  last_depth_ = h;
  last_ = {width_ * f.q, width_ * (face_upstream_ ? f.dq_dy1 : f.dq_dy3)};
  return last_;
}

double FaceLaw::discharge_at(double root) {
  if (std::abs(root - last_depth_) <= 1e-8 * root) return last_.q + last_.dq_dh * (root - last_depth_);
  return (*this)(root).q;
}

}  // namespace canalsim::gates
