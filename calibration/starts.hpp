// Where a calibration's runs start besides the scenario's values: a scan of the parameters whose
// cost is not monotone from there (Parameter::scan), and points screened over the bounds for the
// further starts of a doubtful optimum (calibrate.hpp, CalibrateOptions::starts).
#pragma once

#include <string>
#include <vector>

#include "calibration/levenberg_marquardt.hpp"
#include "calibration/problem.hpp"
#include "core/progress.hpp"

namespace canalsim::calibration {

// `count` points spread over the middle half of the bounds (a Kronecker sequence in the search
// coordinates), ordered by cost; the ones whose simulation fails are dropped.
std::vector<Run> screened_starts(ReplayProblem& problem, int count);

// The start z (at cost `cost_at_z`) with each scanned parameter moved to the value of its scan,
// or its own, that leaves the lowest cost; one simulation per recording and value. Appends to
// `note` where each started, among which values.
std::vector<double> start_at_the_scans(ReplayProblem& fit, std::vector<double> z, double cost_at_z, const ProgressCallback& progress,
                                       std::string& note);

}  // namespace canalsim::calibration
