// Canal physics that the diagnosis catalog (diagnosis/catalog.hpp) does not contain, for blind
// tests that conceal an effect the diagnosis cannot name and should answer `unexplained` to:
//
//   gate backlash   a play of width b in the gate's drive: the gate follows its command only once
//                   the command has taken up the play, and stays put on a reversal until the
//                   command has travelled through it (the play operator, below);
//   depth seepage   level-dependent outlets along a pool, Q = K (h − h0)^p with p = 3/2 by
//                   default: an outflow that grows with the level faster than linearly, so it
//                   changes with the operating point, unlike the catalog's fixed share of inflow.
//
//   Scenario lab = builtin_scenario("lab");
//   Recording rec = simulate_with_backlash(lab, *lab.find_experiment("op2"), 2.0);
//   add_depth_seepage(lab, 0.08);  // 8 % of the inflow at op1's level, through the first pool
#pragma once

#include <string>
#include <vector>

#include "core/recording.hpp"
#include "scenarios/scenario.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::scenarios {

// The play (backlash) operator of width b (Krasnosel'skii & Pokrovskii 1989, "Systems with
// Hysteresis"; Visintin 1994, "Differential Models of Hysteresis"): for a command sequence u_k and an initial output w_{-1} = `initial`,
//
//   w_k = min(u_k + b/2, max(u_k − b/2, w_{k−1})),
//
// so |u_k − w_k| <= b/2 always and w changes only when the command pushes it from one end of the
// play. The operator is rate independent: applied to a piecewise-monotone command it depends only
// on the turning points, so a sequence that holds every level of a piecewise-constant command
// (sampled faster than it switches) gives the output at those samples exactly. Width 0 is the
// identity. Throws std::invalid_argument unless width is finite and >= 0 and initial is finite.
std::vector<double> play_operator(const std::vector<double>& command, double width, double initial);

// The gate openings of an experiment whose controlled gate has a backlash of `backlash_mm` in its
// drive, as a drive recording (scenarios/simulate.hpp, Drive): t_s the instants the gate starts
// to move, u_mm where it heads then, metadata operating_opening_mm the gate's rest before t = 0.
//
// The drive's motor follows the command (clamped to the gate's range) — at once for an ideal
// actuator, at the gate's actuator_speed_m_s otherwise (paper eq. 16) — and the gate follows the
// motor through the play, which starts centred (gate and motor both at the rest opening). With an
// ideal actuator the gate therefore switches exactly at the command's jumps (a PRBS's clock
// edges), to the play operator's output. With a rate-limited one a move starts once the motor has
// crossed the play's dead travel d, d / v after the jump, and the gate then runs with the motor
// at speed v to where the motor's travel ends; the simulator's actuator, driven by these targets
// at the same speed, reproduces that path exactly.
//
// The command is the experiment's input, or the recording `drive.recording` replays; the play and
// the gate range are those of the gate simulate() records (the head gate if controlled, else the
// first controlled one), and every gate the command drives follows the drive. Throws
// InputError when no gate is controlled, when the command is not piecewise constant (a ramp), or
// when backlash_mm is not finite and >= 0.
Recording backlash_drive(const Scenario& scenario, const ExperimentSpec& experiment, double backlash_mm,
                         const Drive& drive = {});

// simulate() with the controlled gate behind a backlash of `backlash_mm` (backlash_drive), its
// recording's u_mm the original command, as a logger that records the command and not the gate
// would write it: only x_up_mm (the gate's position) and the hydraulics show the play. Nothing in
// the recording names the backlash. Throws InputError for an upstream that replays recorded levels
// (the drive recording replaces the replayed one), besides what backlash_drive and simulate throw.
// `simulator`: simulate() unless given (the second simulator's truths, blindtest.hpp).
Recording simulate_with_backlash(const Scenario& scenario, const ExperimentSpec& experiment, double backlash_mm,
                                 const SimulateOptions& options = {}, const Simulator& simulator = {});

struct DepthSeepageOptions {
  int pool = 0;              // 0-based pool that leaks
  int outlets = 5;           // spread evenly along the pool, at x = (k + 1/2) L / outlets
  double exponent = 1.5;     // p of Q = K (h − h0)^p, in [0.5, 3]
  double head_mm = 5.0;      // h − h0 at each outlet in the reference state, > 0
  // The experiment whose operating point (held constant, without seepage) is the reference
  // state; empty = the scenario's first experiment.
  std::string reference_experiment;
};

// Adds a depth-dependent seepage to a pool: `outlets` orifice offtakes of the given exponent
// (solver/reach.hpp), each with its threshold h0 = `head_mm` below the local depth of the
// reference state and K such that together they take `share` of the pool's inflow there:
//
//   K = share · Q_ref / (outlets · head^p),   Q_k(h) = K max(h_k − h0_k, 0)^p.
//
// The reference state is the steady state of the reference experiment's operating point in the
// scenario as given (simulate() with the command held: Newton, or marching if that fails, read
// one sampling period later). With the seepage in place that state's levels drop, so the canal's
// own steady state passes less than `share` (8 % for 10 % asked on the lab at op1). At a lower
// operating level the seepage falls steeply and stops once the level is head_mm below the
// reference; at a higher one it grows as the head's p-th power (25 % of the inflow at op4 for the
// same 10 %). The outlets' discharge_m3s is their share at the reference state, which the
// experiment's events scale as for any orifice. Throws std::invalid_argument unless share is in
// [0, 1), the options are in range and head_mm is below every outlet's reference depth (share 0
// adds nothing), InputError when the reference experiment does not exist.
void add_depth_seepage(Scenario& scenario, double share, const DepthSeepageOptions& options = {});

}  // namespace canalsim::scenarios
