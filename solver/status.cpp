#include "solver/status.hpp"

#include <sstream>

namespace canalsim::solver {

Status Status::error_at(std::string message, double time_s, int reach, int cell) {
  std::ostringstream text;
  text.precision(10);
  // Reach and cell are named only when known (a step that fails as a whole has neither).
  text << message << " (t = " << time_s << " s";
  if (reach >= 0) text << ", reach " << reach;
  if (cell >= 0) text << ", cell " << cell;
  text << ")";
  Status status(text.str());
  status.time_ = time_s;
  status.reach_ = reach;
  status.cell_ = cell;
  return status;
}

}  // namespace canalsim::solver
