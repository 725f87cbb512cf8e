// What a run tells its user besides the recording: the volume balance of the canal over the
// recorded run (docs/numerics.md, "Volume accounting") and any pool whose water rose above its
// walls. Both go into the recording's metadata (docs/recording-format.md); `canalsim simulate`
// prints them on stderr.
#pragma once

#include <string>
#include <vector>

#include "core/recording.hpp"
#include "scenarios/scenario.hpp"
#include "solver/canal.hpp"

namespace canalsim::scenarios {

// Watches the depth of every pool against its wall_height_m: the first time it is exceeded and
// the highest depth reached. A model canal has no banks: the water simply stands higher, so
// overtopping is a warning about the scenario, not an error of the run.
class WallWatch {
 public:
  explicit WallWatch(const Scenario& scenario);
  void observe(const solver::Canal& canal, double time);
  // One text per overtopped pool: "pool 'reach1' (wall 1.1 m) above its wall from t = 3 s,
  // highest depth 627 m at t = 255 s"; empty when no pool overtopped.
  std::vector<std::string> overtopped() const;

 private:
  struct Pool {
    std::string name;
    double wall = 0.0;
    double first_time = -1.0;  // < 0: never above
    double highest = 0.0;
    double highest_time = 0.0;
  };
  std::vector<Pool> pools_;
};

// Writes the balance from t = 0 to `until` (the solver's last step ends at or just past the last
// sample: volume_until_s, volume_inflow_m3, volume_outflow_m3, volume_lateral_m3,
// volume_storage_change_m3, volume_relative_error) and the overtopping warnings
// (warning_overtopping, pools joined by "; ") into the recording's metadata.
void record_run_report(Recording& recording, const solver::VolumeBalance& balance, double until,
                       const WallWatch& walls);

// The lines `canalsim simulate` prints on stderr for a recording that has this metadata:
// "volume balance of NAME [m³]: inflow ..., relative error ..." and one "warning: ..." per pool.
std::vector<std::string> run_report_lines(const Recording& recording);

}  // namespace canalsim::scenarios
