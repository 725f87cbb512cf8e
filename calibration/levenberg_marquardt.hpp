// One bounded Levenberg–Marquardt run of a calibration (Ceres Solver 2.1) on a ReplayProblem:
// Jacobians by the problem's parallel forward differences, progress per iteration, a stop at the
// model's resolution, and a parameter that reaches a bound held there while the gradient pushes it
// outwards (levenberg_marquardt.cpp). calibrate.cpp decides where runs start and which one is kept.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "calibration/problem.hpp"
#include "core/progress.hpp"

namespace canalsim::calibration {

struct Run {
  std::vector<double> z;
  double cost = std::numeric_limits<double>::infinity();
  int iterations = 0;
  std::string report;
  bool converged = false;    // Ceres converged, or stopped at the model's resolution
};

// Relative cost decrease below which a run stops: a precise one for the run that gives the
// answer, a loose one for a further start, which only has to show whether it leads to a better
// basin (and is then continued precisely).
constexpr double kPreciseTolerance = 1e-6, kScoutTolerance = 1e-3;
// The one of a run on a refined grid: there the cost is rough at a thousandth (docs/calibration.md,
// Method 3, "How rough the cost is": a front crossing a sensor within a sample, sharper the finer
// the grid), so a step that gains less than that is not resolved. Measured on the benchmark's
// truth:0 (bench/README.md), the 400-cell run's last nine iterations gained 0.15 %, six of them
// one failed step.
constexpr double kRefinedGridTolerance = 1e-3;

// From z (search coordinates) within the parameters' bounds, at most `max_iterations`; the cost
// is the weighted cost per sample, infinite when no usable solution was found. `run` of `runs`
// for the progress messages. `secant`: Jacobians after the first by secant updates
// (ReplayProblem::use_secant_updates), by differences again after a failed step.
Run levenberg_marquardt(ReplayProblem& problem, std::vector<double> z, int max_iterations, const ProgressCallback& progress,
                        int run, int runs, double function_tolerance, bool secant = false);

}  // namespace canalsim::calibration
