// Steady state of the discretised equations: the state U with L(U) = 0, where L is the
// semi-discrete right-hand side of the finite-volume scheme (Canal::evaluate_rates), boundaries
// and links included. Solved by Newton's method with KINSOL (line search) and the KLU sparse
// direct solver on a Jacobian built by coloured finite differences: cell c's rates depend only on
// cells c-2..c+2 (MUSCL slopes of the two neighbouring faces), so columns 5 cells apart can be
// perturbed together and a Jacobian costs 10 residual evaluations whatever the grid size
// (Curtis, Powell & Reid 1974).
//
// A fixed point of L is a fixed point of every time step (the friction coefficient is taken from
// the stage state), so the result is the state long time marching converges to.
#pragma once

#include <string>

#include "solver/canal.hpp"
#include "solver/status.hpp"

namespace canalsim::solver {

struct SteadyStateOptions {
  // Converged when the Newton step changes no depth by more than this [m]. Range (0, 1e-2].
  double depth_tolerance = 1e-11;
  int max_iterations = 60;  // Newton iterations per attempt, range [1, 1000]
  // When Newton fails: march 3 wave-crossing times and retry, at most this often. Range [0, 20].
  int continuation_attempts = 3;
  // Start Newton from a gradually-varied-flow profile found by shooting on the discharge (one
  // reach between two boundaries, no lateral flow; steady_state.cpp) when it has a smaller
  // residual than the canal's state.
  bool first_guess = true;
  // Newton iterations per Jacobian evaluation (KINSetMaxSetupCalls) when Newton starts from the
  // shooting guess, range [1, 100]: 1 is Newton's method, more is modified Newton (a Jacobian
  // costs 2·5 residual evaluations). From any other start every iteration gets a fresh Jacobian.
  int iterations_per_jacobian = 3;
  // A Newton that stalls short of depth_tolerance is accepted when its last iterate changes no
  // depth faster than this [m/s] and no discharge faster than stalled_discharge_rate × the
  // largest |Q| [1/s]; 0 (the default) never accepts one. The generalised minmod limiter stalls
  // it: on a nearly straight profile its one-sided slopes tie in many cells and switch branch
  // under the smallest change, so the residual has kinks everywhere and the line search fails
  // near the solution (the lab on 200-800 cells: scaled residual 2e-9 to 5e-9 after 60 Newton
  // iterations, where van Leer's reaches 2e-14 in 3). Only the first attempt's stall is accepted
  // (before any continuation march). Range [0, 1e-3] each.
  double stalled_depth_rate = 0.0;
  double stalled_discharge_rate = 0.0;
  Status validate() const;
};

struct SteadyStateSummary {
  Status status;              // failure: not converged (the canal keeps its initial state)
  int iterations = 0;         // Newton iterations
  int residual_evaluations = 0;
  double max_depth_rate = 0.0;      // max |dh/dt| at the solution [m/s]
  double max_discharge_rate = 0.0;  // max |dQ/dt| at the solution [m³/s²]
  // The solution is a stalled Newton's last iterate, accepted by SteadyStateOptions::stalled_*
  // (status ok; `stall` says where Newton stopped).
  bool stalled = false;
  std::string stall;
};

// Replaces the canal's state by the steady state near it (the current state is the first guess)
// at the canal's current time. Boundaries are evaluated at that time; they advance only during
// continuation marches (see continuation_attempts and continuation_span). With a limiter that is
// not differentiable (generalised minmod), a first attempt that fails is retried from van Leer's
// steady state before any march (limiter homotopy, steady_state.cpp). On failure the state is the
// last attempt's starting point.
SteadyStateSummary solve_steady_state(Canal& canal, const SteadyStateOptions& options = {});

// How far past the canal's current time solve_steady_state's continuation marches may advance it
// [s], for the canal's current state. A caller whose boundaries change at some later time (an
// experiment's input starting at t = 0) solves at least this long before it, so that every
// attempt sees the boundaries held.
double continuation_span(const Canal& canal, const SteadyStateOptions& options = {});

}  // namespace canalsim::solver
