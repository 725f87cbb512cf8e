// Hydraulic structures as solver boundaries and links: sluice gates at either end of a pool or
// between two pools, the supply that feeds a head gate (fixed level, PID-controlled reservoir or a
// recorded level series), gate operation (command signal through an actuator, paper eq. 16), and
// a free weir.
//
// Coupling (docs/gates.md): the face state is solved from the gate law together with the Riemann
// invariant that leaves the interior (solver/characteristics.hpp) — not from the lagged interior
// depth — so the discharge is consistent with the pool state at every Runge–Kutta stage and the
// coupling does not chatter when the head across the gate is small. The mass flux is exactly the
// gate discharge, so a structure conserves water exactly. Where the gate issues a jet into the
// pool (free flow), the momentum flux is that of the contracted jet if it exceeds the
// tailwater's: max(M_jet, M_face) is continuous across the regime border and equals M_face when
// the jump is drowned.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "gates/actuator.hpp"
#include "gates/reservoir.hpp"
#include "gates/sluice_gate.hpp"
#include "solver/boundary.hpp"

namespace canalsim::gates {

using TimeSignal = std::function<double(double t)>;

// Opening of a gate over time: a command signal u(t) [m] followed by an ideal actuator or the
// constant-speed actuator of paper eq. (16). Within a step the rate-limited gate moves exactly as
// eq. (16) prescribes from its position at the step's start, so stages see the right opening.
class GateOperation {
 public:
  // Fixed opening.
  explicit GateOperation(double opening, double max_opening);
  // Driven by `command`; speed <= 0 means an ideal actuator.
  GateOperation(TimeSignal command, double speed, double max_opening, double initial_opening);

  double opening(double t) const;     // [m], in [0, max_opening]
  double command(double t) const;     // [m], clamped
  void on_step_accepted(double t, double dt);
  void reset(double t, double opening);  // places the gate (e.g. at the operating point)
  // Replaces the command signal (the linearisation drives the gate with a value it perturbs).
  void set_command(TimeSignal command) { command_ = std::move(command); }

 private:
  TimeSignal command_;
  double speed_ = 0.0;
  double max_opening_ = 0.0;
  double position_ = 0.0;       // at time_
  double time_ = 0.0;
};

// What is upstream of a head gate: a level above the gate sill [m] that may respond to the
// discharge drawn through the gate.
class Supply {
 public:
  virtual ~Supply() = default;
  virtual double level(double t) const = 0;
  virtual void on_step_accepted(double /*t*/, double /*dt*/, double /*outflow*/) {}
};

class FixedLevelSupply final : public Supply {
 public:
  explicit FixedLevelSupply(double level) : level_(level) {}
  double level(double) const override { return level_; }

 private:
  double level_;
};

// A level series (e.g. a recording's y_up), linearly interpolated, held beyond its ends.
class SeriesLevelSupply final : public Supply {
 public:
  SeriesLevelSupply(std::vector<double> time, std::vector<double> level);
  double level(double t) const override;

 private:
  std::vector<double> time_, level_;
};

// The laboratory's upstream pool: a reservoir filled by a pump under PID level control
// (gates/reservoir.hpp); its volume integrates exactly the discharge the gate passed.
class ReservoirSupply final : public Supply {
 public:
  explicit ReservoirSupply(const ReservoirOptions& options) : reservoir_(options) {}
  double level(double) const override { return reservoir_.level(); }
  void on_step_accepted(double, double dt, double outflow) override;
  Reservoir& reservoir() { return reservoir_; }
  const Reservoir& reservoir() const { return reservoir_; }

 private:
  Reservoir reservoir_;
};

struct GateGeometry {
  double width = 0.08;         // [m]
  SluiceGateOptions law;       // law, discharge-coefficient multiplier, leakage
};

// Gate at the upstream end of a pool, fed by a Supply (the paper's motorised upstream gate).
class HeadGateBoundary final : public solver::Boundary {
 public:
  HeadGateBoundary(const GateGeometry& geometry, std::shared_ptr<Supply> supply,
                   std::shared_ptr<GateOperation> operation);
  solver::Flux flux(const solver::BoundaryInput& input) const override;
  void on_step_accepted(double t, double dt, double face_discharge) override;

  double last_discharge() const { return last_discharge_; }  // [m³/s] over the last step
  const Supply& supply() const { return *supply_; }
  const GateOperation& operation() const { return *operation_; }

 private:
  SluiceGate law_;
  double width_;
  std::shared_ptr<Supply> supply_;
  std::shared_ptr<GateOperation> operation_;
  mutable double warm_depth_ = -1.0;  // Newton warm start only; results do not depend on it
  double last_discharge_ = 0.0;
};

// Gate at the downstream end of a pool, discharging onto a tail level [m above the sill]
// (0 = free outfall).
class TailGateBoundary final : public solver::Boundary {
 public:
  TailGateBoundary(const GateGeometry& geometry, TimeSignal tail_level,
                   std::shared_ptr<GateOperation> operation);
  solver::Flux flux(const solver::BoundaryInput& input) const override;
  void on_step_accepted(double t, double dt, double face_discharge) override;
  double last_discharge() const { return last_discharge_; }

 private:
  SluiceGate law_;
  double width_;
  TimeSignal tail_level_;
  std::shared_ptr<GateOperation> operation_;
  mutable double warm_depth_ = -1.0;
  double last_discharge_ = 0.0;
};

// Gate between two pools (check structure): the upstream pool's C+ invariant, the downstream
// pool's C− invariant and the gate law give the discharge and both face depths.
class GateLink final : public solver::Link {
 public:
  GateLink(const GateGeometry& geometry, std::shared_ptr<GateOperation> operation);
  solver::LinkFlux flux(const solver::LinkInput& input) const override;
  void on_step_accepted(double t, double dt, double face_discharge) override;
  double last_discharge() const { return last_discharge_; }
  const GateOperation& operation() const { return *operation_; }

 private:
  SluiceGate law_;
  double width_;
  std::shared_ptr<GateOperation> operation_;
  double last_discharge_ = 0.0;
};

// Free rectangular weir at a downstream end: Q = C w (h - p)^{3/2} for h > p, else a wall.
class WeirBoundary final : public solver::Boundary {
 public:
  WeirBoundary(double crest_height, double coefficient, double width);
  solver::Flux flux(const solver::BoundaryInput& input) const override;

 private:
  double crest_, coefficient_, width_;
};

// Pump at a downstream end drawing a fixed discharge Q_p out of the pool, throttled linearly to 0
// as the depth at the intake falls from `stop_depth` to 0 (a pump protection cut-out; it keeps
// a pool from being drained below dry):  Q(h) = Q_p min(1, h / stop_depth).
// The face depth comes from the outgoing invariant (as for the weir), so the mass flux is exactly
// Q(h_face).
class PumpBoundary final : public solver::Boundary {
 public:
  PumpBoundary(double discharge, double stop_depth);
  solver::Flux flux(const solver::BoundaryInput& input) const override;
  void on_step_accepted(double t, double dt, double face_discharge) override;
  double last_discharge() const { return last_discharge_; }

 private:
  double discharge_, stop_depth_;
  double last_discharge_ = 0.0;
};

// Low-level face solves, exposed for tests.
namespace coupling {

// Face depth at `end` of a pool such that the discharge the outgoing invariant allows equals
// `discharge_law(h)` (with derivative), on the subcritical branch. Safeguarded Newton inside a
// bracket; `guess` <= 0 means none. Returns nullopt when no subcritical root exists (the face
// chokes: the caller imposes critical flow).
struct LawValue {
  double q;     // [m³/s]
  double dq_dh; // [m²/s]
};
std::optional<double> solve_face_depth(const solver::Section& section, double gravity,
                                       solver::End end, const solver::InteriorState& cell,
                                       const std::function<LawValue(double)>& discharge_law,
                                       double guess);

// Supercritical (jet) depth of discharge Q with specific energy E in the section: the shallow
// root of E = h + Q²/(2 g A(h)²).
double jet_depth(const solver::Section& section, double gravity, double discharge, double energy);

}  // namespace coupling

}  // namespace canalsim::gates
