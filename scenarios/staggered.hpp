// A second simulator of a gated pool, written apart from solver/ and gates/, so that tests,
// calibration and diagnosis have a truth that canalsim's own model cannot represent exactly —
// not only other numerics of the same code, but another scheme and another gate-law
// regularisation, as an independent simulator of the laboratory canal would have.
//
//   scheme         the staggered grid of Stelling & Duinmeijer (2003, "A staggered conservative
//                  scheme for every Froude number in rapidly varied shallow water flows", Int. J.
//                  Numer. Meth. Fluids 43): depths at cell centres, velocities at faces; the
//                  continuity equation with upwind depths (second order, van Albada's limiter),
//                  the momentum equation in its momentum-conserving form (the velocity advected
//                  by the upwind cell-centre discharge), friction semi-implicit; explicit in time
//                  at a Courant number of its own. The finite-volume model (solver/) is a MUSCL
//                  Godunov scheme on the conserved variables.
//   gates          Swamee's laws (1992) at both gates, with this simulator's own regularisation
//                  near zero head — the head's power h^0.7 taken as h (h² + ε²)^-0.15, smooth
//                  through zero — and its own floor of the regime border over the tail, y3 + √((y_lc −
//                  y3)² + δ²) where the model uses max(y_lc, κ y3). Each gate's face flux is
//                  implicit in the depth of the cell beside it (a scalar root per gate and step),
//                  as a gate near zero head is too stiff for an explicit flux.
//   reservoir      the pump-fed upstream pool under PID control (gates/reservoir.hpp states the
//                  model), integrated with the controller evaluated at the start of each step.
//
// The command is the experiment's input (scenarios/simulate.hpp command_input): steps end at its
// jumps and at every sampling instant. Sensors read the true depths through the scenario's
// offsets, noise and resolution (eq. 17).
#pragma once

#include "core/recording.hpp"
#include "scenarios/scenario.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::scenarios {

struct StaggeredOptions {
  int cells = 300;                       // of the pool, >= 3
  double courant = 0.5;                  // (|u| + √(g h)) Δt / Δx, in (0, 0.9]
  double zero_head_smoothing_m = 0.002;  // ε of the submerged law near zero head, >= 0
  double border_margin_m = 0.002;        // δ of the regime border's floor over the tail, > 0
  double settle_s = 900.0;               // at most, marching to the steady state before t = 0
  // A recording whose u_mm drives the gate instead of the experiment's input (as
  // scenarios::simulate's); its recorded upstream level is not used.
  Drive drive;
};

// Runs one experiment of a scenario of one rectangular pool between a controlled head gate and
// a downstream gate, weir or wall, fed by a fixed level or a pump-fed reservoir, with offtakes
// (fixed, or orifices sized beforehand). The recording has
// the columns of scenarios::simulate (t_s, u_mm, x_up_mm, y_up_mm, y_dw_mm, y_dwe_mm, q_lps,
// regime). Throws InputError naming the scenario key for anything else (several pools, a
// trapezoidal section, events, a sensor delay, a recorded upstream level) and std::runtime_error when the canal
// does not settle within settle_s or a depth turns non-positive.
Recording simulate_staggered(const Scenario& scenario, const ExperimentSpec& experiment,
                             const StaggeredOptions& options = {});

// The second simulator as a Simulator (simulate.hpp): the drive taken from the SimulateOptions,
// everything else from `options`.
Simulator staggered_simulator(const StaggeredOptions& options = {});

}  // namespace canalsim::scenarios
