// A time offset between the command and the level columns, of either sign: a command and levels
// logged on two clocks, a gate that starts moving late, levels stamped when they are written
// rather than when they were read. Every response then sits early or late against its command,
// and the level just below the gate (y_dw, 0.1 m from it in the lab) answers a gate move within
// a sample or two, so a few tenths of a second matter. The default set has no parameter for it,
// and a fit without one bends the hydraulics to the shift: on four 80 s recordings of the
// six-parameter truth (docs/calibration.md, "A time offset between command and levels"), levels
// 0.3 s early or late left a cost of 0.93-0.98 against 0.033, Cd free at 0.60 / 0.39 (truth 0.9).
//
// After the first fit, the levels' delay (`sensor_delay_s`, a re-observation of the same
// simulations: no simulation per point) is scanned at the estimates. Where the best delay lowers
// the cost by more than kTimeOffsetGain, calibrate() fits it with the default set.
#pragma once

#include <vector>

#include "calibration/replay.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

// The fraction of the cost a time offset must explain to be fitted. Measured at the first fit's
// estimates (100 cells; four 80 s recordings of the six-parameter truth): levels 0.05 s early
// explain 0.38 of the cost, 0.1 s early or late 0.74 / 0.77, 0.3 s early or late 0.90 / 0.74.
// With command and levels on one clock the scan's best (a delay of 0.009 s: the coarser grid's
// dispersion) explains 0.038 on a 200-cell truth.
constexpr double kTimeOffsetGain = 0.15;

struct TimeOffsetScan {
  double delay_s = 0.0;        // the best delay of the levels (negative: they lead the command)
  double cost_at_zero = 0.0;   // weighted cost per sample with the scenario's own delay
  double cost_at_best = 0.0;   // ... with the best one
  // Whether the offset explains more than kTimeOffsetGain of the cost.
  bool worth_fitting() const { return cost_at_best < (1.0 - kTimeOffsetGain) * cost_at_zero; }
};

// The cost of `scenario` on `recordings` for delays of the level sensors within range_s of the
// scenario's own, in steps of `step_s`, the best refined to 1 ms by golden-section search: one
// simulation per recording in all.
TimeOffsetScan scan_time_offset(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings,
                                const ReplayOptions& replay, int threads, double range_s = 2.0, double step_s = 0.05);

}  // namespace canalsim::calibration
