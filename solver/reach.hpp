// A reach: the state of one prismatic channel stretch in structure-of-arrays form (one contiguous
// array per quantity, one value per cell), plus the work arrays of the scheme so that a step never
// allocates. Cell i covers [i dx, (i+1) dx] with x = 0 at the upstream end.
#pragma once

#include <string>
#include <vector>

#include "solver/options.hpp"
#include "solver/section.hpp"

namespace canalsim::solver {

class Reach {
 public:
  explicit Reach(const ReachSpec& spec);  // spec must pass validate(spec)

  const std::string& name() const { return name_; }
  int cells() const { return cells_; }
  double length() const { return length_; }
  double cell_length() const { return dx_; }
  double x_centre(int i) const { return (i + 0.5) * dx_; }
  const Section& section() const { return section_; }
  double manning_n() const { return manning_n_; }

  // Conserved state: wetted area A [m²] and discharge Q [m³/s] per cell. Callers may write them
  // between steps (e.g. to set an initial state); keep A >= 0.
  std::vector<double>& area() { return area_; }
  const std::vector<double>& area() const { return area_; }
  std::vector<double>& discharge() { return discharge_; }
  const std::vector<double>& discharge() const { return discharge_; }
  // Bed elevation z per cell [m].
  const std::vector<double>& bed() const { return bed_; }
  // Lateral inflow per unit length q_l [m²/s] per cell (negative: withdrawal). Set it between
  // steps; it is held constant over a step. Inflow brings no x-momentum; withdrawal removes the
  // local momentum q_l u.
  std::vector<double>& lateral_inflow() { return lateral_inflow_; }
  const std::vector<double>& lateral_inflow() const { return lateral_inflow_; }

  // Level-dependent lateral outlets: outlet k withdraws
  //   Q_k = K_k max(h_cell - invert_k, 0)^p_k            [m³/s]
  // from its cell. p = 1/2 is a gravity orifice, Q = Cd A sqrt(2 g Δh) with the constant
  // Cd A sqrt(2 g) = K_k (e.g. Henderson 1966, §6.2); p = 3/2 a side weir of crest length L over
  // the invert, K = (2/3) Cd L sqrt(2 g) (the rectangular weir formula), or a seepage that grows
  // faster than the depth. The solver re-evaluates Q_k from each Runge–Kutta stage's depths
  // (update_outlets, called by the Canal), adding it to lateral_inflow() as −Q_k/dx on top of
  // what the caller put there, so steady-state solves and the volume balance see it.
  struct Outlet {
    int cell = 0;
    double coefficient = 0.0;   // K [m^(3-p)/s], >= 0
    double invert_depth = 0.0;  // invert height above the cell's bed [m]
    double exponent = 0.5;      // p: the power of the head, in [0.5, 3]
    double applied = 0.0;       // Q_k of the last evaluation [m³/s] (its share of lateral_inflow)
    bool at_downstream_end = false;  // withdraws at the end face (see end_withdrawal), not the cell
  };
  // Returns the index; the coefficient's unit is m^(3-p)/s.
  int add_outlet(int cell, double coefficient, double invert_depth, double exponent = 0.5);
  // An outlet at the reach's downstream end face, just upstream of the boundary or link there;
  // its head is the face depth. Returns the index.
  int add_end_outlet(double coefficient, double invert_depth, double exponent = 0.5);
  const std::vector<Outlet>& outlets() const { return outlets_; }
  void set_outlet_coefficient(int k, double coefficient);
  // Q_k for the current state [m³/s]; for an end outlet, what the last flux evaluation withdrew.
  double outlet_discharge(int k) const;
  // Re-evaluates every cell outlet from the depths h_ of the current stage.
  void update_outlets();

  // Withdrawal at the downstream end face [m³/s], >= 0: an offtake just upstream of the check.
  // The Canal hands the boundary or link there the flow that goes on past the offtake (the end
  // cell's discharge less the withdrawal), so the structure's face state is the one downstream of
  // the offtake, with the level continuous across it; the reach's face passes the structure's flux
  // plus the withdrawal. A withdrawal inside a cell instead leaves that cell carrying the mean of
  // what enters and leaves it, which the HLL flux to its neighbour can pass only through a depth
  // dip of about ΔQ / (2 c T) (docs/asce-canals.md). The fixed part is set by the caller (0 by
  // default; held over a step, stopped while the end cell is dry); end outlets add theirs.
  double& fixed_end_withdrawal() { return fixed_end_withdrawal_; }
  double fixed_end_withdrawal() const { return fixed_end_withdrawal_; }
  bool has_end_withdrawal() const;
  // Evaluates the end-face withdrawal for face depth h [m] (fixed part + end outlets), records
  // it for the volume balance and each end outlet's share, and returns it [m³/s].
  double evaluate_end_withdrawal(double face_depth, double dry_depth);
  double last_end_withdrawal() const { return stage_end_withdrawal_; }

  double depth(int i) const { return section_.depth(area_[i]); }
  double level(int i) const { return bed_[i] + depth(i); }
  double volume() const;  // Σ A dx [m³]

 private:
  friend class Canal;
  friend struct ReachKernels;
  friend double lateral_volume_rate(const Reach&, double);
  std::string name_;
  int cells_;
  double length_, dx_;
  Section section_;
  double manning_n_;
  std::vector<double> area_, discharge_, bed_, lateral_inflow_;
  std::vector<Outlet> outlets_;
  double fixed_end_withdrawal_ = 0.0;
  double stage_end_withdrawal_ = 0.0;  // end_withdrawal of the last compute_fluxes [m³/s]
  // Scheme work arrays (solver/scheme.cpp): start-of-step state, primitive variables, 1/A and
  // their limited slopes per cell, fluxes per face (cells + 1 faces; face f is left of cell f).
  std::vector<double> area0_, discharge0_;
  std::vector<double> h_, u_, eta_, dh_, du_, deta_, inv_area_;
  std::vector<double> face_mass_, face_momentum_left_, face_momentum_right_;
};

}  // namespace canalsim::solver
