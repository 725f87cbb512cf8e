// From a scenario to a recording: build the canal (solver reaches, gates, supply, offtakes), bring
// it to the steady state of its operating point, run an experiment and sample it with the
// scenario's sensors (docs/recording-format.md).
//
//   const Scenario lab = builtin_scenario("lab");
//   Recording rec = simulate(lab, *lab.find_experiment("op1"));
//   write_recording("op1.csv", rec);
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "gates/structures.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"
#include "scenarios/signals.hpp"
#include "solver/canal.hpp"
#include "solver/steady_state.hpp"

namespace canalsim::scenarios {

// A scenario turned into solver objects, with handles on what the sensors read.
struct BuiltCanal {
  solver::Canal canal;
  std::shared_ptr<gates::Supply> supply;                  // null without a head gate
  std::shared_ptr<gates::ReservoirSupply> reservoir;      // the supply, when it is a reservoir
  std::shared_ptr<gates::HeadGateBoundary> head_gate;     // null without a head gate
  std::vector<std::shared_ptr<gates::GateLink>> gate_links;
  std::shared_ptr<gates::TailGateBoundary> tail_gate;     // null unless downstream kind = gate
  // The gate the experiment drives; with no controlled gate (driven = false) the first gate,
  // whose opening and discharge u_mm and q_lps then record.
  std::shared_ptr<gates::GateOperation> controlled;
  double controlled_max_opening = 0.0;
  bool driven = false;
  // The discharge through the controlled gate over the last step [m³/s].
  std::function<double()> controlled_discharge;
  // The head inflow of an upstream of kind "discharge" (events change it); null otherwise.
  std::shared_ptr<double> head_inflow;
  // Every offtake, per pool, for the experiment's events.
  struct Offtake {
    int cell = 0;
    bool at_end = false;             // withdrawn at the pool's downstream end face (x_m = length)
    int outlet = -1;                 // index among the reach's outlets; -1 = fixed discharge
    double design_m3s = 0.0;         // the scenario's (design) discharge
    double design_coefficient = 0.0; // orifice K at design [m^(3 - exponent)/s]
    double current_m3s = 0.0;        // fixed offtake: the discharge withdrawn now
  };
  std::vector<std::vector<Offtake>> offtakes;
  // Openings of the head gate (if any) and the gates between pools, as built ("auto" resolved) [m].
  std::vector<double> openings;
  // Bed elevation at each pool's downstream end x = L [m].
  std::vector<double> check_bed;
  // The command signal of the controlled gate (its jumps end time steps: simulate.cpp).
  SignalPtr command;
  // Depth at the check of pool i (0-based) [m]: the water level extrapolated from the last two
  // cell centres to x = L (the one-sided end reconstruction of the scheme, solver/scheme.cpp)
  // above check_bed. The last cell's own level sits half a cell upstream, which on a backwater
  // curve is millimetres lower.
  double check_depth(int pool) const;
};

// Applies one event (new offtake discharge, new head inflow) to a built canal, as the run does at
// the event's time.
void apply_event(BuiltCanal& canal, const EventSpec& event);

// What drives an experiment besides its own input: a recording whose u_mm replaces the input
// signal (and whose y_up_mm feeds the head gate when `use_recorded_upstream`).
struct Drive {
  const Recording* recording = nullptr;
  bool use_recorded_upstream = false;
};

struct SimulateOptions {
  // Called with the fraction done in [0, 1], about every 1% of the run.
  ProgressCallback progress;
  Drive drive;
  // Time marching before t = 0 when the steady-state (Newton) solve is off or fails [s]: at most
  // this long, stopping once the canal has settled (settle.cpp, settled) but never before
  // the experiment's settle_s.
  double settle_time = 600.0;
  bool use_steady_state_solver = true;
  // Past the ceilings of scenarios/run_cost.hpp (`--allow-long`).
  bool allow_long_run = false;
  // When Newton fails: throw std::runtime_error naming the failure (true), or march for (at most)
  // settle_time with the command held at its operating point and warn, naming the state the
  // experiment then starts from (false). Never silent. A Newton stalled at a limiter's kinks
  // within initial_steady_state_options' bounds has not failed: the recording's initial_state
  // metadata names the stall.
  bool require_steady_state = false;
  // Receives the failed-steady-state warning (one line, without the "canalsim: warning: "
  // prefix); unset, it is printed to stderr.
  std::function<void(const std::string&)> warning;
  // Called with the canal at the end of the run (tests read the volume balance and final state).
  std::function<void(const BuiltCanal&)> on_finish;
};

// Builds the canal for `experiment` with every gate at its initial/operating opening and the
// command signal attached (throws InputError naming the scenario key on inconsistent input).
BuiltCanal build_canal(const Scenario& scenario, const ExperimentSpec& experiment,
                       const Drive& drive = {});

// The gate command u(t) [m] of an experiment: operating point plus its input signal; the drive
// recording's u_mm when given (resting before t = 0 at the recording's operating point).
SignalPtr command_input(const ExperimentSpec& experiment, const Drive& drive);
std::function<double(double)> command_signal(const ExperimentSpec& experiment, const Drive& drive);

// The options of the steady-state solve an experiment starts from: the scenario's tolerance, and
// a Newton stalled at a limiter's kinks accepted when no depth changes faster than the time
// marching that replaces a failed Newton accepts as settled (docs/numerics.md, "Stalls at the
// limiter's kinks"). `canalsim linearize` solves its operating point with them too.
solver::SteadyStateOptions initial_steady_state_options(const Scenario& scenario, const ExperimentSpec& experiment,
                                                        const SimulateOptions& options = {});

// Runs one experiment and returns its recording (columns t_s, u_mm, x_up_mm, y_up_mm, y_dw_mm,
// y_dwe_mm, q_lps, regime; the regime by the paper's conditions (8)/(10) on the true levels).
// Throws InputError on bad input and std::runtime_error naming time and cell when the solver
// fails.
Recording simulate(const Scenario& scenario, const ExperimentSpec& experiment,
                   const SimulateOptions& options = {});

// Something that runs an experiment as simulate() does: simulate() itself, or the second
// simulator (staggered.hpp staggered_simulator), for truths of another scheme.
using Simulator = std::function<Recording(const Scenario&, const ExperimentSpec&, const SimulateOptions&)>;

}  // namespace canalsim::scenarios
