#include "solver/status.hpp"

#include <string>

#include "core/format.hpp"

namespace canalsim::solver {

Status Status::error_at(std::string message, double time_s, int reach, int cell) {
  // Reach and cell are named only when known (a step that fails as a whole has neither).
  std::string text = message + " (t = " + format_g(time_s, 10) + " s";
  if (reach >= 0) text += ", reach " + std::to_string(reach);
  if (cell >= 0) text += ", cell " + std::to_string(cell);
  text += ")";
  Status status(text);
  status.time_ = time_s;
  status.reach_ = reach;
  status.cell_ = cell;
  return status;
}

}  // namespace canalsim::solver
