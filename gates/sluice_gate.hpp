// Sluice-gate discharge laws, flow-regime conditions and their derivatives.
//
// Notation (per unit width, SI units): y1 upstream depth [m], y3 depth downstream of the gate
// (tailwater, after the jump) [m], a gate opening [m], q discharge per unit width [m^2/s],
// g gravity [m/s^2]. Multiply q by the gate width b for the discharge in m^3/s.
//
// Swamee (1992), "Sluice-gate discharge equations", J. Irrig. Drain. Eng. 118(1), 56-60:
//
//   free flow        q_f = 0.864 a sqrt(g y1) ((y1 - a) / (y1 + 15 a))^0.072
//   submerged flow   q_s = q_f (y1 - y3)^0.7 / [ 0.32 (y_lc - y1)^0.7 + (y1 - y3)^0.7 ]
//   with the limit   y_lc = 0.81 y3 (y3 / a)^0.72                    (paper eq. 23)
//
// The published form of the free law is q = Cd a sqrt(2 g y1) with
// Cd = 0.611 ((y1 - a)/(y1 + 15 a))^0.072 (0.864 = 0.611 sqrt 2). The flow is free when
// y1 > y_lc (paper condition 8) and submerged when y3 < y1 < y_lc (paper condition 10). At the
// border y1 = y_lc the bracket's first term vanishes, so q_s = q_f: the law is continuous there.
// Its slope is not: d q_s / d y1 ~ (y_lc - y1)^-0.3 is unbounded at the border, and
// d q_s / d y1 ~ (y1 - y3)^-0.3 at zero head (the simple law eq. 11 behaves like (y1-y3)^-0.5).
//
// The paper's (Gharab, Feliu-Batlle & Rivas-Perez 2019) simpler laws, selectable for comparison:
//
//   free flow        q_f = Cd a sqrt(2 g y1)                              (paper eq. 9)
//   submerged flow   q_s = Cd a sqrt(2 g (y1 - y3))                       (paper eq. 11)
//
// with Cd = 0.6 and the same regime conditions (8)/(10); these jump at the regime border.
//
// Extensions beyond the published laws, each chosen so that q stays continuous:
// - Reverse head (y3 > y1): the law is applied with the roles of the two sides swapped and the
//   sign of q reversed, so q(y1, y3, a) = -q(y3, y1, a) exactly.
// - Wide-open gate near zero head: where y_lc < κ y3 (κ = 1.05 by default: a gate opened wider
//   than ~0.75 y3), Swamee's condition would call the flow free up to zero head and q would jump
//   to reverse flow. The flow law floors its border at κ y3 (SluiceGateOptions::
//   border_floor_ratio), so the flow submerges as the head vanishes and q falls continuously to 0.
//   classify_regime keeps the paper's published condition.
// - Near zero head, optionally (SluiceGateOptions::zero_head, 0 by default): the submerged law's
//   power of the head turns linear below a head h0, so its slope stays finite.
// - Closed gate (a <= 0 and no leakage): a wall, q = 0.
// - Leakage: the law sees the opening max(a, 0) + leakage_opening, so a "closed" gate with
//   leakage passes the flow of a small opening.
// - Gate lifted out of the water (a >= y1 on the upstream side): the gate no longer controls and
//   the section passes critical flow for the upstream energy. We take the energy as the upstream
//   depth (velocity head neglected, as the gate laws themselves do), so y_c = 2/3 y1 and
//   q_c = sqrt(g) y_c^{3/2} = 0.5443 sqrt(g) y1^{3/2}.
//   Swamee's free law is y1^{3/2} sqrt(g) f(a/y1) with f(r) = 0.864 r ((1-r)/(1+15r))^0.072,
//   which rises to a maximum f = 0.54611 at r = 0.928 and then falls to 0 at r = 1 (outside the
//   range the law was fitted on). Because the maximum exceeds 0.5443 by 0.33 %, the law meets
//   critical flow at r_c = 0.9057 (see critical_opening_ratio()); above that opening we freeze the
//   opening the law sees at r_c y1. The result is continuous in y1, y3 and a, with a kink at
//   a = r_c y1, and equal to q_c for a >= y1. If the discharge-coefficient multiplier is so small
//   that the scaled law never reaches critical flow (multiplier < 0.99675 = 0.5443/0.5461 for Swamee), the
//   opening is frozen at the law's maximum instead and q jumps up to q_c when the gate leaves the
//   water: the jump is q_c - m f_max sqrt(g) y1^{3/2}, i.e. (0.5443 - 0.5461 m)/0.5443 relative
//   (0.2 % at m = 0.995, 10 % at m = 0.9).
//   The simple law reaches critical flow at r_c = 0.5443 / (m Cd sqrt 2) (0.641 for Cd = 0.6).
//   Drowned flow with the gate out of the water keeps the submergence factor evaluated with the
//   frozen opening, which is again continuous.
#pragma once

#include <string>

#include "core/status.hpp"

namespace canalsim::gates {

inline constexpr double standard_gravity = 9.81;  // m/s^2

enum class GateLaw {
  swamee,  // Swamee (1992), continuous across the regime border (default)
  simple,  // paper eq. 9 (free) and eq. 11 (submerged) with a constant Cd
};

// Regime of the flow through a gate, by the paper's conditions (8) and (10).
enum class GateRegime {
  closed,        // opening <= 0 or no water on the upstream side: no flow
  free,          // condition (8): y_up > y_lc
  submerged,     // condition (10): y_dwe <= y_up <= y_lc (includes zero head)
  out_of_water,  // the gate is above the upstream surface (a >= y_up): critical flow
};

const char* to_string(GateLaw law);
const char* to_string(GateRegime regime);

struct SluiceGateOptions {
  GateLaw law = GateLaw::swamee;
  // Multiplies the discharge coefficient of the law (1 = as published). Diagnosis scales it to
  // explain a gain mismatch. Range (0, 10].
  double discharge_coefficient_multiplier = 1.0;
  // The multiplier in submerged flow (condition 10), range (0, 10]; 0 (the default) = the same
  // as discharge_coefficient_multiplier. Swamee's law is least reliable near the regime border and near zero head, so
  // calibration lets the two differ. The simple submerged law (eq. 11) uses it alone (it jumps at
  // the border anyway). Swamee's law stays continuous: with the submergence factor F in [0, 1]
  // (F = 1 at the border, 0 at zero head) the multiplier of submerged flow is
  //   m(F) = m_s + (m_f - m_s) F,
  // m_f at the border, tending to m_s as the flow drowns.
  double submerged_discharge_coefficient_multiplier = 0.0;
  double submerged_multiplier() const {
    return submerged_discharge_coefficient_multiplier > 0.0 ? submerged_discharge_coefficient_multiplier
                                                            : discharge_coefficient_multiplier;
  }
  // Cd of the simple laws (paper eq. 9 and 11; "generally close to 0.6"). Range (0, 2].
  double simple_discharge_coefficient = 0.6;
  // Extra opening that leaks under a closed gate [m]. Range [0, 1].
  double leakage_opening = 0.0;
  // Regularisation of the submerged law near zero head [m], range [0, 1]; 0 = the law as published.
  // Both submerged laws grow like a power of the head h = y1 - y3 (h^0.7 in Swamee's, h^0.5 in
  // eq. 11), with an unbounded slope at zero head, and neither was fitted on heads of a few mm:
  // there viscosity and the drowned jet govern, and every simulator regularises the law its own
  // way. With zero_head = h0 > 0 the power h^p becomes
  //   h (h + h0)^(p - 1),
  // linear in the head below h0 (slope h0^(p-1), finite), the published power above it
  // (relative change (1 - p) h0 / h for h >> h0). The discharge at the regime border (F = 1) and
  // at zero head (0) is unchanged, so the law stays continuous. Calibration fits h0
  // (calibration/parameters.cpp) to a gate that runs nearly drowned, like the lab's head gate at
  // op3/op4 (head ~1 mm).
  double zero_head = 0.0;
  // A discharge coefficient that varies smoothly with the opening, the shape real gate ratings
  // take (Cd of a sluice gate rises or falls by several per cent over its range of openings, and
  // the published laws' contraction term does not follow every gate). The law's discharge, free
  // and submerged, is multiplied by
  //   c(a) = exp(β x + γ x²),  x = ln(a / a_ref) clamped to [-4, 4],
  // a the opening the law sees: a power law of the opening (Cd ∝ a^β) when γ = 0, curved in
  // log-log otherwise, 1 at a_ref. β = γ = 0 (the default) is the law as published. With the
  // submerged multiplier's blend in the submergence factor F (above), the coefficient varies
  // smoothly with opening and submergence. Out of the water the law keeps c at the frozen
  // opening, so the flow is continuous in the opening but is c(r_c y1) times critical flow.
  double opening_exponent = 0.0;   // β, range [-2, 2]
  double opening_curvature = 0.0;  // γ, range [-2, 2]
  double reference_opening = 0.025;  // a_ref [m], range (0, 100]
  // The floor κ of the flow law's regime border, in units of the tailwater depth: the border is
  // max(y_lc, κ y3), range (1, 2]. Swamee's law was not fitted where y_lc falls below the tail (a
  // gate opened wider than ~0.75 y3), so there the border is a choice: with it the flow is
  // submerged until the head reaches (κ − 1) y3, 3 mm on the lab's 60 mm at κ = 1.05, and frees
  // above. Every simulator makes this choice its own way; the submergence factor of a gate running
  // at a millimetre of head (the lab's head gate at op3/op4) and its slope in the tail, which sets
  // how the gate reflects the waves coming back up the pool, follow it. Calibration fits it
  // (calibration/parameters.cpp border_floor_ratio).
  double border_floor_ratio = 1.05;
  double gravity = standard_gravity;  // m/s^2, range (0, 100]

  // Ok, or one line naming the field and its allowed range (core/status.hpp).
  [[nodiscard]] Status validate() const;
};

// Discharge per unit width and its partial derivatives (for the Newton solve of the face state).
struct GateFlow {
  double q = 0.0;       // m^2/s, positive from side 1 to side 3
  double dq_dy1 = 0.0;  // d q / d y1   [m/s]
  double dq_dy3 = 0.0;  // d q / d y3   [m/s]
  double dq_da = 0.0;   // d q / d a    [m/s]
  GateRegime regime = GateRegime::closed;
  bool reverse = false;  // the flow goes from side 3 to side 1 (y3 > y1)
};

// Paper eq. (23): the upstream level at the free/submerged border,
// y_lc = 0.81 y_dwe (y_dwe / x_up)^0.72. Returns +infinity for a closed gate (x_up <= 0) and 0
// for a dry downstream side (y_dwe <= 0).
double limit_condition_level(double y_dwe, double x_up);

// The paper's conditions (8)/(10) applied in the direction of the head: with y_up >= y_dwe,
// free when y_up > y_lc(y_dwe, x_up), submerged otherwise; with y_dwe > y_up the roles are
// swapped (reverse flow). A gate at or above the upstream surface is out_of_water; x_up <= 0 or a
// dry upstream side is closed.
GateRegime classify_regime(double y_up, double y_dwe, double x_up);

// Swamee's free-flow law alone, per unit width, for 0 < a < y1 (0 outside).
double swamee_free_discharge(double y1, double a, double gravity = standard_gravity);

// Critical flow per unit width for the upstream energy taken as the depth y1:
// q_c = sqrt(g) (2/3 y1)^{3/2}.
double critical_discharge(double y1, double gravity = standard_gravity);

// A sluice-gate law with its options validated and its constants precomputed. Evaluation is a
// pure function of (y1, y3, a): no state changes, safe to call from several threads.
class SluiceGate {
 public:
  SluiceGate() : SluiceGate(SluiceGateOptions{}) {}
  // Throws std::invalid_argument with validate()'s message when the options are invalid.
  explicit SluiceGate(const SluiceGateOptions& options);

  // Discharge per unit width [m^2/s], signed (positive from side 1 to side 3).
  double discharge(double y1, double y3, double a) const { return evaluate(y1, y3, a).q; }
  // Discharge, analytic partial derivatives, regime and direction.
  GateFlow evaluate(double y1, double y3, double a) const;

  // What a face solve can reuse between evaluations: it varies one depth while the other and the
  // opening stay fixed, so either the free discharge (fixed upstream depth, head gate) or the
  // regime border (fixed tailwater, tail gate) is the same at every evaluation; each costs a `pow`.
  // Entries are keyed on their exact arguments, so results are bit-identical with and without a
  // memo. One memo per solve (a local variable): it is not thread-safe to share.
  struct Memo {
    double free_y1 = -1.0, free_a = -1.0, free_q = 0.0, free_d_y1 = 0.0, free_d_a = 0.0;
    double border_y3 = -1.0, border_a = -1.0, border = 0.0;
  };
  GateFlow evaluate(double y1, double y3, double a, Memo& memo) const;

  // Opening ratio a / y_up above which the law sees a frozen opening (see the header comment).
  double critical_opening_ratio() const { return cap_ratio_; }
  // Whether the (scaled) law reaches critical flow continuously; false means q jumps when the
  // gate leaves the water.
  bool reaches_critical_flow() const { return reaches_critical_; }
  const SluiceGateOptions& options() const { return options_; }

 private:
  struct Partials {
    double q = 0.0, d_y1 = 0.0, d_y3 = 0.0, d_a = 0.0;
  };
  struct SeenOpening;
  struct Border;
  Partials forward(double y1, double y3, double a, GateRegime& regime, Memo* memo) const;
  Partials free_flow(double y1, double a_seen) const;
  SeenOpening seen_opening(double y1, double a, double geometric) const;
  Partials free_discharge(double y1, const SeenOpening& seen, Memo* memo) const;
  Border flow_border(double y3, double a_seen, Memo* memo) const;
  Partials submerged_simple(double y1, double y3, const SeenOpening& seen) const;
  Partials submerged_swamee(double y1, double y3, const SeenOpening& seen, const Partials& free,
                            const Border& border) const;
  Partials rated(const Partials& law, const SeenOpening& seen) const;

  SluiceGateOptions options_;
  double cap_ratio_ = 1.0;
  bool reaches_critical_ = true;
};

// The gate law as one face solve sees it: the depth on one side of the gate varies (the face depth
// of the pool the gate closes), the other depth and the opening are fixed for the whole solve. It
// keeps the memo of the fixed terms and the last evaluation, from which discharge_at() gives the
// discharge at the root without evaluating again when the root is within 1e-8 h of it (the last
// Newton step: the linear extrapolation is exact to ~1e-16 relative). One per solve.
class FaceLaw {
 public:
  // `face_is_upstream_side`: the varying depth is y1 (a gate at the downstream end of its pool);
  // otherwise it is y3 (a head gate fed from a supply at y1 = fixed_depth). Discharges in m³/s.
  FaceLaw(const SluiceGate& law, double width, bool face_is_upstream_side, double fixed_depth,
          double opening)
      : law_(&law), width_(width), face_upstream_(face_is_upstream_side), fixed_(fixed_depth),
        opening_(opening) {}
  struct Value {
    double q;      // [m³/s]
    double dq_dh;  // d q / d(face depth) [m²/s]
  };
  Value operator()(double face_depth);
  double discharge_at(double root);

 private:
  const SluiceGate* law_;
  double width_;
  bool face_upstream_;
  double fixed_, opening_;
  SluiceGate::Memo memo_;
  double last_depth_ = -1.0;
  Value last_{0.0, 0.0};
};

}  // namespace canalsim::gates
