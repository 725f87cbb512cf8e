// The fit table of a calibration: RMS and Nrmse (paper eq. 19) per recording and channel, before
// and after, with the series for the report's plots.
#pragma once

#include <vector>

#include "calibration/calibrate.hpp"
#include "calibration/problem.hpp"

namespace canalsim::calibration {

// Appends to c.fits and c.series a row per recording of `problem` and weighted channel: the
// recorded series against `before` (the scenario as given) and `after` (the calibrated model).
void add_fits(const ReplayProblem& problem, const std::vector<Channels>& before, const std::vector<Channels>& after,
              bool validation, Calibration& c);

enum class FitSide { before, after };

// Replaces one side's figures and series in the rows add_fits() made for `problem` (the same
// recordings, `validation` as then) by those of `prediction`: the scenario as given, when the
// calibration ran on another grid or law (before), or the model written (after).
void restate_fits(const ReplayProblem& problem, const std::vector<Channels>& prediction, bool validation, FitSide side,
                  Calibration& c);

}  // namespace canalsim::calibration
