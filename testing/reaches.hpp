// Reaches for the solver's tests: a prismatic channel on a flat bed, at rest at one depth.
#pragma once

#include <cstddef>

#include "solver/options.hpp"

namespace canalsim::testing {

// `cells` cells over `length` m of `section`, Manning n `manning_n`, every cell `depth` deep and
// at rest.
inline solver::ReachSpec uniform_reach(double length, int cells, solver::Section section, double manning_n,
                                       double depth) {
  solver::ReachSpec spec;
  spec.length = length;
  spec.cells = cells;
  spec.section = section;
  spec.manning_n = manning_n;
  spec.initial_depth.assign(static_cast<std::size_t>(cells), depth);
  return spec;
}

}  // namespace canalsim::testing
