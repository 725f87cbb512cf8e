// The calibrated scenario as a file: the user's scenario text (or the built-in's) with every
// calibrated key replaced, the gate laws compared and the grid calibrated on, and the
// [calibration] tables `diagnose` reads what the calibration left open from (diagnosis/baseline.hpp).
// `canalsim calibrate -o` writes it and the Python package returns it as a Scenario.
#pragma once

#include <string>
#include <vector>

#include "calibration/calibrate.hpp"

namespace canalsim::diagnosis {

// Where the calibration came from, for the file's first comment and its messages.
struct CalibratedScenarioSource {
  std::string scenario;                 // the built-in name or file calibrated
  std::vector<std::string> recordings;  // the recordings' names, as the comment lists them
  std::string destination;              // the file it is written to, naming it in errors
};

// The calibrated scenario's TOML text. Parsed back and compared with the calibration, so a text
// that would not read back is never returned (std::runtime_error naming the key).
std::string calibrated_scenario_toml(const std::string& text, const calibration::Calibration& c,
                                     const CalibratedScenarioSource& source);

}  // namespace canalsim::diagnosis
