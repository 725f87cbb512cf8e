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
  Status validate() const;
};

struct SteadyStateSummary {
  Status status;              // failure: not converged (the canal keeps its initial state)
  int iterations = 0;         // Newton iterations
  int residual_evaluations = 0;
  double max_depth_rate = 0.0;      // max |dh/dt| at the solution [m/s]
  double max_discharge_rate = 0.0;  // max |dQ/dt| at the solution [m³/s²]
};

// Replaces the canal's state by the steady state near it (the current state is the first guess)
// at the canal's current time. Boundaries are evaluated at that time; they advance only during
// continuation marches (see continuation_attempts). On failure the state is the last attempt's
// starting point.
SteadyStateSummary solve_steady_state(Canal& canal, const SteadyStateOptions& options = {});

}  // namespace canalsim::solver
