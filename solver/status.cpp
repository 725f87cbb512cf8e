#include "solver/status.hpp"

#include <sstream>

namespace canalsim::solver {

Status Status::error_at(std::string message, double time_s, int reach, int cell) {
  std::ostringstream text;
  text.precision(10);
  text << message << " (t = " << time_s << " s, reach " << reach << ", cell " << cell << ")";
  Status status(text.str());
  status.time_ = time_s;
  status.reach_ = reach;
  status.cell_ = cell;
  return status;
}

}  // namespace canalsim::solver
