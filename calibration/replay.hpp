// A recording replayed through a scenario: its gate command drives the controlled gate (and, when
// asked, its upstream level feeds the head gate), the canal starts from the steady state of the
// recording's operating point, and the simulated channels are sampled at the recording's instants.
// Calibration fits scenario parameters with it; diagnosis compares candidate physics with it.
//
//   const ReplayOptions o;
//   const Replay r = prepare_replay(recording, scenario, o);
//   const Channels truth = replay_true(scenario, r, o);        // ideal sensors
//   const Channels model = observe(truth, sensor_model_of(scenario.sensors), r.period_s);
//
// Replays are independent: run several with core/parallel.hpp parallel_for.
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "calibration/observe.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

struct ReplayOptions {
  // Channels compared (those a recording lacks are skipped).
  std::vector<std::string> channels = {"y_dwe_mm", "y_dw_mm", "y_up_mm", "x_up_mm", "q_lps"};
  double fit_fraction = 0.5;     // leading share of each recording used for fitting; (0, 1]
  // Replay the recorded y_up_mm as the upstream level (when the recording has it).
  bool use_recorded_upstream = false;
  // The recorded command changed somewhere in the sample interval before it shows; the replay
  // switches this many samples earlier so that, on average, it is not late (0 = at the sample).
  double command_lead_samples = 0.5;  // [0, 1]
  // A clocked command (a PRBS) switches on a grid t0 + m T; when one period and phase are
  // consistent with every sampled change, the replay switches at the reconstructed instants
  // instead (command_switch_times), which removes the sampling jitter of the input.
  bool reconstruct_clock = true;
  // Also when the recorded upstream level is replayed: the drive then holds rows at the sample
  // and the switch instants (off keeps the diagnosis' sampled drive in that case).
  bool clock_with_upstream = false;
  double settle_time_s = 600.0;  // SimulateOptions::settle_time; >= 0
  // Leading seconds of every recording left out of the compared series (at most a third of a
  // recording is dropped). None by default: the replay starts from the steady state of the
  // recording's own initial state, so every sample after it is comparable.
  double warmup_s = 0.0;         // >= 0
  // Start each replay from the steady state at the recording's own first upstream level
  // (Replay::initial_upstream_mm, less the scenario's y_up sensor offsets) instead of the
  // scenario's upstream level_m (upstream kinds "level" and "reservoir").
  bool start_at_recorded_level = false;
  // Called with a warning of the simulation (a failed steady state, see scenarios/simulate.hpp);
  // unset, it is printed to stderr.
  std::function<void(const std::string&)> warning;
};

// One recording made ready for replay.
struct Replay {
  std::string name;
  Recording drive;            // t_s shifted: first sample at 0, command lead applied
  std::vector<double> t, u, regime;   // after the warm-up; t from the recording's first sample
  Channels data;              // the compared channels the recording has (after the warm-up)
  double operating_point_mm = 0.0;
  std::size_t skip = 0;       // warm-up samples dropped from every series
  bool clocked = false;       // the drive switches at reconstructed clock instants
  std::size_t n = 0, n_fit = 0;   // samples after the warm-up; the leading n_fit are fitted
  double period_s = 0.13;     // the scenario's sensor period
  // Where the recording says it starts: its `initial_y_up_mm` metadata, else the mean recorded
  // y_up_mm over the samples before the command first changes (at most 1 s); NaN without y_up.
  double initial_upstream_mm = std::numeric_limits<double>::quiet_NaN();
};

// The gate a replay drives: the head gate when controlled, else the first controlled gate between
// pools; null when there is none.
const scenarios::GateSpec* controlled_gate(const scenarios::Scenario& scenario);

// The instants at which a sampled, clocked command changed: if one clock (period T, phase t0)
// puts a grid point inside every interval (t[k-1], t[k]] where u changes, the grid points;
// otherwise empty. Periods are searched near the shortest spacing between changes.
std::vector<double> command_switch_times(const std::vector<double>& t, const std::vector<double>& u);

// Problems that make recordings unusable with the scenario, one line each naming the recording:
// sampling period different from the scenario's sensors, missing channels, gate commands or
// positions outside the controlled gate's range, too few samples. Empty when all are usable.
std::vector<std::string> check_recordings(const scenarios::Scenario& scenario,
                                          const std::vector<Recording>& recordings);

// The recording made ready for replay. The operating point (the opening the canal settles at
// before the first sample) is the recording's operating_opening_mm metadata when it is a valid
// opening of the controlled gate, else its first command.
Replay prepare_replay(const Recording& recording, const scenarios::Scenario& scenario, const ReplayOptions& options);

// The replay's channels with ideal sensors (no resolution, noise, delay or offset), sampled at
// the recording's instants after the warm-up: the channels of replay.data the simulation has.
// Throws what scenarios::simulate throws.
Channels replay_true(const scenarios::Scenario& scenario, const Replay& replay, const ReplayOptions& options);

// Cost weights of the compared channels: w_c = 1 / s_c², s_c the mean within-recording standard
// deviation of channel c, floored (0.5 mm for levels and gate position, 0.05 l/s for flow) so
// that a nearly constant channel (a PID-held upstream level) does not dominate the cost.
struct ChannelWeights {
  std::map<std::string, double> scale, weight;
};
ChannelWeights channel_weights(const std::vector<Replay>& replays, const std::vector<std::string>& channels);

}  // namespace canalsim::calibration
