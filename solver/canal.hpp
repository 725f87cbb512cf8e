// Canal: reaches joined by links, with a boundary at each free end, advanced in time by the
// finite-volume scheme (docs/numerics.md). The common case is one reach with two boundaries:
//
//   Canal canal;                                   // SolverOptions defaults
//   ReachSpec spec; spec.length = 5; spec.cells = 100; ...
//   if (auto st = canal.add_reach(spec); !st) ...  // st.message() names the bad field
//   canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(0.002));
//   canal.set_boundary(0, End::downstream, std::make_shared<CriticalDepthBoundary>());
//   if (auto st = canal.advance_to(60.0); !st) ...  // non-finite state: time, reach and cell
//   canal.sample(0, 4.9, Quantity::depth); canal.total_balance().error();
//
// Scheme per step (Audusse et al. 2004 hydrostatic reconstruction, HLL flux, MUSCL on η, h, u,
// Heun's SSP-RK2, semi-implicit Manning friction); dt = cfl · min dx / max |wave speed| over the
// faces of the first stage, clipped to the end time. Recordings sample the state between steps
// (scenarios/simulate.cpp interpolates in time), so no step is cut short to hit a sample time.
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "solver/boundary.hpp"
#include "solver/options.hpp"
#include "solver/reach.hpp"
#include "solver/status.hpp"

namespace canalsim::solver {

// Volume accounting [m³] since the canal was created (or reset_balance()). Inflow and outflow
// are the time integrals of the mass flux through the upstream and downstream end faces
// (positive downstream), lateral the integral of Σ q_l dx, and positivity_correction the volume
// added when round-off negative areas are set to 0. error() is what does not add up; it is
// round-off for a conservative scheme.
struct VolumeBalance {
  double initial_storage = 0.0;
  double storage = 0.0;
  double inflow = 0.0;
  double outflow = 0.0;
  double lateral = 0.0;
  double positivity_correction = 0.0;
  double storage_change() const { return storage - initial_storage; }
  double error() const {
    return storage_change() - (inflow - outflow + lateral + positivity_correction);
  }
  // |error| relative to the largest of the volumes involved.
  double relative_error() const;
};

enum class Quantity { depth, level, area, discharge, velocity, froude };

// How Canal::evaluate_rates treats the slope limiter where it is not differentiable.
enum class LimiterKinks {
  as_scheme,  // the scheme's own limiter (what a time step uses)
  centred,    // the centred slope at kinks (solver/rates_jacobian.hpp, docs/linearization.md)
};

struct StepStatistics {
  long steps = 0;           // accepted steps
  long retries = 0;         // rejected and retried steps
  double last_dt = 0.0;
  double min_dt = std::numeric_limits<double>::infinity();
};

class Canal {
 public:
  explicit Canal(SolverOptions options = {});
  // Validates the options; a Canal with invalid options refuses to add reaches and to step.
  const Status& options_status() const { return options_status_; }
  const SolverOptions& options() const { return options_; }
  // Changes the slope limiter in place (no other option may change after construction): the
  // steady-state solver's limiter homotopy (steady_state.cpp) solves with van Leer's first.
  void set_limiter(Limiter limiter) { options_.limiter = limiter; }

  // Adds a reach (index reach_count() - 1 on success).
  Status add_reach(const ReachSpec& spec);
  int reach_count() const { return static_cast<int>(reaches_.size()); }
  Reach& reach(int r) { return reaches_.at(static_cast<std::size_t>(r)); }
  const Reach& reach(int r) const { return reaches_.at(static_cast<std::size_t>(r)); }

  // End conditions. Each end of each reach needs exactly one boundary or one link.
  Status set_boundary(int reach, End end, std::shared_ptr<Boundary> boundary);
  // Joins the downstream end of `upstream` to the upstream end of `downstream`.
  Status connect(int upstream, int downstream, std::shared_ptr<Link> link);
  // Checks that every end is closed and the state is finite and non-negative.
  Status check_ready() const;

  double time() const { return time_; }
  void set_time(double t) { time_ = t; }

  // One time step of at most max_dt. On failure the state is left at the start of the step.
  Status step(double max_dt = std::numeric_limits<double>::infinity());
  // Steps until time() == t_end exactly (the last step is clipped to land on it).
  Status advance_to(double t_end);

  // The value of a quantity at x in a reach now (linear interpolation between cell centres,
  // constant beyond the first and last centres).
  double sample(int reach, double x, Quantity quantity) const;

  VolumeBalance balance(int reach) const;
  VolumeBalance total_balance() const;
  void reset_balance();  // starts the accounting afresh from the current state

  const StepStatistics& statistics() const { return stats_; }

  // The semi-discrete right-hand side L(U) of the scheme for the current state at time t, the
  // rates a step integrates: dA/dt and dQ/dt per cell, friction explicit (the update treats it
  // linearly implicitly with k from the stage state, so a state with L(U) = 0 is a fixed point of
  // every step, whatever dt). Layout: cells of all reaches in order, rates[2c] = dA/dt,
  // rates[2c + 1] = dQ/dt. Takes no step and advances no boundary state (used by the steady-state
  // solver, solver/steady_state.hpp).
  // With LimiterKinks::centred the slope limiter takes the centred slope where it is not
  // differentiable (StageSettings::centred_kinks): for the linearisation's Jacobian only.
  void evaluate_rates(double t, std::vector<double>& rates, LimiterKinks kinks = LimiterKinks::as_scheme);
  // The mass flux through an end face of a reach at the last flux evaluation (a step's stage or
  // evaluate_rates) [m³/s], positive downstream; at a downstream end it includes an end-face
  // withdrawal (Reach::fixed_end_withdrawal).
  double end_face_discharge(int reach, End end) const;
  int total_cells() const;
  // The flux the boundary at `end` of `reach` returns at time t for an adjacent face state `cell`
  // (the steady-state solver's first guess asks it). False, and *out untouched, when that end is
  // joined by a link or has no boundary. Advances no boundary state.
  bool boundary_flux(int reach, End end, const InteriorState& cell, double t, Flux* out) const;

 private:
  struct EndConnection {
    std::shared_ptr<Boundary> boundary;
    std::shared_ptr<Link> link;
    int other_reach = -1;
  };
  struct Accumulators {  // per reach
    double initial_storage = 0, inflow = 0, outflow = 0, lateral = 0, correction = 0;
    double stage_inflow = 0, stage_outflow = 0, stage_lateral = 0;  // weighted over a step
  };

  double compute_fluxes(double t, bool centred_kinks = false);  // all reaches, returns min over reaches of dx / max speed
  Status apply_update(double dt, double alpha, double weight, bool final_stage, bool* reject);
  void save_start_state();
  void restore_start_state();
  Status find_non_finite(double t) const;

  SolverOptions options_;
  Status options_status_;
  std::vector<Reach> reaches_;
  std::vector<EndConnection> upstream_ends_, downstream_ends_;
  std::vector<Accumulators> acc_;
  double time_ = 0.0;
  StepStatistics stats_;
};

}  // namespace canalsim::solver
