// The grid check of a calibration: its optimum re-simulated on twice the cells, how much the
// levels and the cost move (GridCheck, calibrate.hpp), and the replays on twice the cells kept
// per point, which the doubt about a first run, the check whether a refinement follows and the
// grid check at the optimum share (calibrate.cpp).
#pragma once

#include <optional>
#include <vector>

#include "calibration/calibrate.hpp"
#include "calibration/problem.hpp"

namespace canalsim::calibration {

// The replays of the problem's scenario at one point on twice the cells, kept for the last point
// asked: one simulation per recording on twice the cells, which the doubt and the grid check at
// the optimum each made before.
class TwiceTheCells {
 public:
  explicit TwiceTheCells(ReplayProblem& problem) : problem_(problem) {}
  // Before the sensors (what a refined grid starts from); throws when a simulation fails.
  const std::vector<Channels>& truth_at(const std::vector<double>& z) { return replay(z).truth; }
  // As the problem's sensors read them.
  const std::vector<Channels>& observed_at(const std::vector<double>& z) { return replay(z).observed; }

 private:
  struct Replayed {
    std::vector<double> z;
    std::vector<Channels> truth, observed;
  };
  const Replayed& replay(const std::vector<double>& z);

  ReplayProblem& problem_;
  std::optional<Replayed> last_;
};

// The optimum re-simulated on a grid with twice the cells of every pool (`fine`, as observed;
// the first prediction of the re-estimate on twice the cells): how much the levels and the cost
// (`cost`, the weighted cost per sample of `at_optimum`) move.
GridCheck grid_check(const ReplayProblem& problem, const std::vector<Channels>& fine,
                     const std::vector<Channels>& at_optimum, double cost);

}  // namespace canalsim::calibration
