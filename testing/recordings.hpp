// Recordings written by hand for the tests and benchmarks: the columns every fitter reads.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/recording.hpp"

namespace canalsim::testing {

// A logger's recording of the gate and the downstream level: the instants t_s, the gate command
// u_mm and the downstream-end level y_dwe_mm, named `source` (a file name, as the messages say).
inline Recording command_and_level(std::string source, std::vector<double> t_s, std::vector<double> u_mm,
                                   std::vector<double> y_dwe_mm) {
  Recording rec;
  rec.source = std::move(source);
  rec.set_column(columns::time, std::move(t_s));
  rec.set_column(columns::gate_command, std::move(u_mm));
  rec.set_column(columns::level_downstream_end, std::move(y_dwe_mm));
  return rec;
}

}  // namespace canalsim::testing
