#include "solver/reach.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalsim::solver {

Reach::Reach(const ReachSpec& spec)
    : name_(spec.name),
      cells_(spec.cells),
      length_(spec.length),
      dx_(spec.length / spec.cells),
      section_(spec.section),
      manning_n_(spec.manning_n) {
  const auto n = static_cast<std::size_t>(cells_);
  bed_ = spec.bed_elevation.empty() ? std::vector<double>(n, 0.0) : spec.bed_elevation;
  area_.assign(n, 0.0);
  discharge_.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!spec.initial_depth.empty()) area_[i] = section_.area(spec.initial_depth[i]);
    if (!spec.initial_discharge.empty()) discharge_[i] = spec.initial_discharge[i];
  }
  lateral_inflow_.assign(n, 0.0);
  for (auto* v : {&area0_, &discharge0_, &h_, &u_, &eta_, &dh_, &du_, &deta_, &inv_area_}) v->assign(n, 0.0);
  for (auto* v : {&face_mass_, &face_momentum_left_, &face_momentum_right_}) v->assign(n + 1, 0.0);
}

double Reach::volume() const {
  double sum = 0.0;
  for (double a : area_) sum += a;
  return sum * dx_;
}

namespace {

// The outlet law of reach.hpp. The orifice's square root is kept apart from std::pow: it is exact
// (correctly rounded), so orifice runs do not move with the library's pow.
double outlet_law(const Reach::Outlet& o, double depth) {
  const double head = std::max(depth - o.invert_depth, 0.0);
  return o.coefficient * (o.exponent == 0.5 ? std::sqrt(head) : std::pow(head, o.exponent));
}

double valid_exponent(double exponent) {
  if (!(exponent >= 0.5 && exponent <= 3.0)) {
    throw std::invalid_argument("Reach outlet exponent = " + std::to_string(exponent) + ": expected a value in [0.5, 3]");
  }
  return exponent;
}

}  // namespace

int Reach::add_outlet(int cell, double coefficient, double invert_depth, double exponent) {
  outlets_.push_back({std::clamp(cell, 0, cells_ - 1), std::max(coefficient, 0.0), invert_depth,
                      valid_exponent(exponent), 0.0});
  return static_cast<int>(outlets_.size()) - 1;
}

void Reach::set_outlet_coefficient(int k, double coefficient) {
  outlets_.at(static_cast<std::size_t>(k)).coefficient = std::max(coefficient, 0.0);
}

int Reach::add_end_outlet(double coefficient, double invert_depth, double exponent) {
  outlets_.push_back({cells_ - 1, std::max(coefficient, 0.0), invert_depth, valid_exponent(exponent), 0.0, true});
  return static_cast<int>(outlets_.size()) - 1;
}

double Reach::outlet_discharge(int k) const {
  const Outlet& o = outlets_.at(static_cast<std::size_t>(k));
  return o.at_downstream_end ? o.applied : outlet_law(o, depth(o.cell));
}

double Reach::evaluate_end_withdrawal(double face_depth, double dry_depth) {
  double q = face_depth > dry_depth ? fixed_end_withdrawal_ : 0.0;
  for (Outlet& o : outlets_) {
    if (!o.at_downstream_end) continue;
    o.applied = outlet_law(o, face_depth);
    q += o.applied;
  }
  stage_end_withdrawal_ = q;
  return q;
}

bool Reach::has_end_withdrawal() const {
  if (fixed_end_withdrawal_ != 0.0) return true;
  return std::any_of(outlets_.begin(), outlets_.end(), [](const Outlet& o) { return o.at_downstream_end; });
}

void Reach::update_outlets() {
  for (Outlet& o : outlets_) {
    if (o.at_downstream_end) continue;  // withdrawn at the face (Canal::compute_fluxes)
    const auto i = static_cast<std::size_t>(o.cell);
    const double q = outlet_law(o, h_[i]);
    lateral_inflow_[i] += (o.applied - q) / dx_;  // replaces the outlet's previous share
    o.applied = q;
  }
}

}  // namespace canalsim::solver
