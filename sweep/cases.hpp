// The cases of a sweep and the scenario each runs.
//
// The grid keys combine as a Cartesian product, the first [[vary]] key slowest (nested loops in
// the file's order). Each grid point is drawn `draws` times for the distribution keys; a point is
// one set of values of every key. Each point runs every experiment: a case is one point and one
// experiment, numbered
//
//   case = point × experiments + experiment,     point = grid point × draws + draw.
//
// A drawn value depends only on the seed, the point and the key's position in the file, never
// on which process or thread computes the case, nor on the order cases are computed in.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "scenarios/scenario.hpp"
#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {

struct Case {
  std::size_t index = 0;
  std::size_t point = 0;
  std::size_t experiment = 0;  // into SweepFile::experiments
  std::vector<double> values;  // one per [[vary]] key, in the file's order
};

std::size_t grid_point_count(const SweepFile& sweep);
std::size_t case_count(const SweepFile& sweep);
Case case_at(const SweepFile& sweep, std::size_t index);

// A number as the table and the scenario text write it: the shortest text that reads back as the
// same double (0.009, 0.30000000000000004), an integer without a point, so that the number in the
// table is the number simulated, bit for bit.
std::string exact_number(double value);

// The base scenario's text with the case's values (and the sweep's duration_s) written in:
// "experiment.KEY" as KEY of the case's experiment. A case with fewer values than keys writes the
// first ones only (the file's checks blame a refused point on one key so).
std::string case_scenario_text(const SweepFile& sweep, const Case& c);
// That text parsed; throws InputError when the scenario refuses it.
scenarios::Scenario case_scenario(const SweepFile& sweep, const Case& c);

}  // namespace canalsim::sweep
