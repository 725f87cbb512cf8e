// End conditions and internal links of a canal.
//
// A Boundary returns the flux through the end face of a reach given the interior cell next to it;
// a Link joins the last cell of one reach to the first cell of the next and returns one mass flux
// (the same on both sides, so the link conserves water exactly) and a momentum flux for each side.
// Fluxes are positive in the +x (downstream) direction at both ends. The solver calls flux() once
// per Runge–Kutta stage — possibly again for a retried step, so flux() must not change the
// object's state — and on_step_accepted() once per accepted step with the face discharge that was
// actually applied over that step (the RK-weighted mean of the stage mass fluxes), which is where
// a reservoir integrates its volume or an actuator moves.
//
// How a structure (e.g. a sluice gate at a downstream end) should compute its flux:
//   1. w = outgoing_invariant(section, g, end, input.cell)       (characteristics.hpp)
//   2. solve_face_state(section, g, end, input.cell, law) with law(h_b) = gate discharge for the
//      face depth h_b (and the tailwater, gate opening, time): the face depth is the one where the
//      discharge the characteristic can deliver equals the gate's;
//   3. return face_state_flux(section, g, h_b, Q_b) — mass flux exactly Q_b.
// If is_supercritical_outflow(...) the interior controls the face: return the interior flux.
#pragma once

#include <functional>
#include <memory>

#include "solver/characteristics.hpp"
#include "solver/flux.hpp"
#include "solver/section.hpp"

namespace canalsim::solver {

struct BoundaryInput {
  End end = End::downstream;
  InteriorState cell{};
  Section section{};
  double gravity = 9.81;
  double time = 0.0;         // time of the Runge–Kutta stage [s]
  double cell_length = 0.0;  // dx [m]
};

class Boundary {
 public:
  virtual ~Boundary() = default;
  // Flux through the end face; max_speed is the largest |wave speed| at the face (CFL).
  virtual Flux flux(const BoundaryInput& input) const = 0;
  // Called once per accepted step [t, t + dt] with the face discharge actually used [m³/s].
  virtual void on_step_accepted(double /*t*/, double /*dt*/, double /*face_discharge*/) {}
};

struct LinkInput {
  InteriorState upstream_cell{};    // last cell of the upstream reach
  InteriorState downstream_cell{};  // first cell of the downstream reach
  Section upstream_section{};
  Section downstream_section{};
  double gravity = 9.81;
  double time = 0.0;
};

struct LinkFlux {
  double mass = 0.0;                 // m³/s, leaves the upstream reach and enters the downstream one
  double momentum_upstream = 0.0;    // momentum flux seen by the upstream reach's last cell
  double momentum_downstream = 0.0;  // momentum flux seen by the downstream reach's first cell
  double max_speed = 0.0;
};

class Link {
 public:
  virtual ~Link() = default;
  virtual LinkFlux flux(const LinkInput& input) const = 0;
  virtual void on_step_accepted(double /*t*/, double /*dt*/, double /*face_discharge*/) {}
};

using TimeFunction = std::function<double(double t)>;

// Reflective wall: HLL flux against the mirror state (h, −u); mass flux exactly 0.
class WallBoundary final : public Boundary {
 public:
  Flux flux(const BoundaryInput& input) const override;
};

// Zero-gradient (transmissive) boundary: the exact flux of the interior state. Lets waves out
// approximately; the free outflow of a dam break.
class TransmissiveBoundary final : public Boundary {
 public:
  Flux flux(const BoundaryInput& input) const override;
};

// Imposed free-surface level η(t) = z + h [m] (or depth, if `is_depth`), with the face velocity
// from the outgoing invariant. Supercritical outflow ignores the level (interior controls).
class FixedLevelBoundary final : public Boundary {
 public:
  explicit FixedLevelBoundary(TimeFunction level, bool is_depth = false)
      : level_(std::move(level)), is_depth_(is_depth) {}
  static std::shared_ptr<FixedLevelBoundary> depth(double h) {
    return std::make_shared<FixedLevelBoundary>([h](double) { return h; }, true);
  }
  static std::shared_ptr<FixedLevelBoundary> level(double eta) {
    return std::make_shared<FixedLevelBoundary>([eta](double) { return eta; }, false);
  }
  Flux flux(const BoundaryInput& input) const override;

 private:
  TimeFunction level_;
  bool is_depth_;
};

// Imposed discharge Q(t) [m³/s] (positive downstream: an inflow at the upstream end), the face
// depth from the outgoing invariant (solve_face_state). Mass flux exactly Q(t).
class FixedDischargeBoundary final : public Boundary {
 public:
  explicit FixedDischargeBoundary(TimeFunction discharge) : discharge_(std::move(discharge)) {}
  static std::shared_ptr<FixedDischargeBoundary> constant(double q) {
    return std::make_shared<FixedDischargeBoundary>([q](double) { return q; });
  }
  Flux flux(const BoundaryInput& input) const override;

 private:
  TimeFunction discharge_;
};

// Free overfall at a downstream end: the face is critical (u_b = c_b) on the outgoing C+
// characteristic, u_b + Φ(h_b) = w+; for a rectangle 3 c_b = u_i + 2 c_i. Interior flow that is
// already supercritical leaves with the interior flux; flow towards upstream sees a wall.
class CriticalDepthBoundary final : public Boundary {
 public:
  Flux flux(const BoundaryInput& input) const override;
};

// Continuous channel joining two reaches (possibly different sections and a bed step): HLL with
// hydrostatic reconstruction between the two adjacent face states, as an interior face. With
// different sections each side solves the Riemann problem in its own section (exact at rest) and
// the shared mass flux is their mean.
class ContinuousLink final : public Link {
 public:
  LinkFlux flux(const LinkInput& input) const override;
};

}  // namespace canalsim::solver
