// Writing a calibrated scenario: the user's scenario file (or the built-in text) with the
// calibrated keys replaced in place, each with its standard deviation in a comment, so the file
// keeps its layout and comments and `simulate`, `diagnose` and `calibrate` read it as any other.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace canalsim::calibration {

struct KeyEdit {
  // A scenario key as the parameter catalog names it: "table.key", "table.sub.key" or
  // "array[i].key" (i 1-based, e.g. "pools[1].manning_n").
  std::string key;
  double value = 0.0;
  std::string comment;   // written after the value as "# comment"
  std::string text;      // a value written as it is ("\"simple\""), instead of `value`, when not empty
};

// The TOML text with every edit applied: the key's line replaced where the table holds it,
// inserted after the table's header where it does not, the table appended where the file has
// none. Throws InputError naming the key when it cannot be placed (an array element the file
// lacks). Values are written with 10 significant digits.
std::string edit_scenario_toml(const std::string& text, const std::vector<KeyEdit>& edits);

// The TOML text with its [calibration.std] table (docs/scenarios.md) replaced by one holding
// `deviations` — calibration parameter name → one standard deviation — appended at the end; names with a
// dot ("manning_n.1") are quoted. A previous [calibration] or [calibration.std] table is removed
// first, so a calibrated file calibrated again carries only the new figures. Non-finite
// deviations (not determined by the data) are left out.
// `baseline_rms_mm` (the primary residual left on the baseline) goes into [calibration] before it,
// the same per level channel into [calibration.baseline_rms], its part slower than the fast band
// into [calibration.baseline_slow_rms], and each parameter's deviation with the others held at
// their estimates into [calibration.std_alone] after it.
std::string with_calibration_table(const std::string& text, const std::map<std::string, double>& deviations,
                                   double baseline_rms_mm = 0.0,
                                   const std::map<std::string, double>& deviations_alone = {},
                                   const std::map<std::string, double>& baseline_rms_by_channel = {},
                                   const std::map<std::string, double>& baseline_slow_rms_by_channel = {});

}  // namespace canalsim::calibration
