#include "solver/options.hpp"

#include <cmath>
#include <sstream>

#include "core/format.hpp"

namespace canalsim::solver {
namespace {

std::string describe(const std::string& field, double value, const std::string& range) {
  return field + " = " + format_g(value, 10) + " is outside the allowed range " + range;
}

// Checks an optional per-cell array: empty, or `cells` finite values (non-negative if asked).
Status check_cell_array(const std::string& field, const std::vector<double>& values, int cells,
                        bool non_negative) {
  if (values.empty()) return Status::ok();
  if (static_cast<long>(values.size()) != cells) {
    std::ostringstream text;
    text << field << " has " << values.size() << " values; expected " << cells
         << " (one per cell) or none";
    return Status::error(text.str());
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if (!std::isfinite(v) || (non_negative && v < 0.0)) {
      std::ostringstream text;
      text << field << "[" << i << "] = " << format_g(v) << " is outside the allowed range "
           << (non_negative ? "[0, inf) (finite)" : "finite values");
      return Status::error(text.str());
    }
  }
  return Status::ok();
}

}  // namespace

Status validate(const SolverOptions& o) {
  if (!(o.cfl > 0.0 && o.cfl <= 1.0)) return Status::error(describe("SolverOptions::cfl", o.cfl, "(0, 1]"));
  if (o.order != SpatialOrder::first && o.order != SpatialOrder::second)
    return Status::error("SolverOptions::order must be SpatialOrder::first or SpatialOrder::second");
  if (o.limiter != Limiter::van_leer && o.limiter != Limiter::generalised_minmod)
    return Status::error("SolverOptions::limiter must be Limiter::van_leer or Limiter::generalised_minmod");
  if (!(o.limiter_theta >= 1.0 && o.limiter_theta <= 2.0))
    return Status::error(describe("SolverOptions::limiter_theta", o.limiter_theta, "[1, 2]"));
  if (!(o.gravity > 0.0 && std::isfinite(o.gravity)))
    return Status::error(describe("SolverOptions::gravity", o.gravity, "(0, inf)"));
  if (!(o.dry_depth >= 0.0 && o.dry_depth <= 0.01))
    return Status::error(describe("SolverOptions::dry_depth", o.dry_depth, "[0, 0.01] m"));
  if (!(o.max_time_step > 0.0))
    return Status::error(describe("SolverOptions::max_time_step", o.max_time_step, "(0, inf] s"));
  if (o.max_step_retries < 0 || o.max_step_retries > 60)
    return Status::error(describe("SolverOptions::max_step_retries", o.max_step_retries, "[0, 60]"));
  return Status::ok();
}

Status validate(const ReachSpec& s) {
  const std::string p = "ReachSpec(" + s.name + ")::";
  if (!(s.length > 0.0 && std::isfinite(s.length)))
    return Status::error(describe(p + "length", s.length, "(0, inf) m"));
  if (s.cells < 2) return Status::error(describe(p + "cells", s.cells, "[2, inf)"));
  if (!(s.section.bottom_width >= 0.0 && std::isfinite(s.section.bottom_width)))
    return Status::error(describe(p + "section.bottom_width", s.section.bottom_width, "[0, inf) m"));
  if (!(s.section.side_slope >= 0.0 && std::isfinite(s.section.side_slope)))
    return Status::error(describe(p + "section.side_slope", s.section.side_slope, "[0, inf)"));
  if (!(s.section.bottom_width + s.section.side_slope > 0.0))
    return Status::error(p + "section: bottom_width and side_slope are both 0; at least one must be positive");
  if (!(s.manning_n >= 0.0 && std::isfinite(s.manning_n)))
    return Status::error(describe(p + "manning_n", s.manning_n, "[0, inf) s/m^(1/3)"));
  if (auto st = check_cell_array(p + "bed_elevation", s.bed_elevation, s.cells, false); !st) return st;
  if (auto st = check_cell_array(p + "initial_depth", s.initial_depth, s.cells, true); !st) return st;
  if (auto st = check_cell_array(p + "initial_discharge", s.initial_discharge, s.cells, false); !st)
    return st;
  return Status::ok();
}

}  // namespace canalsim::solver
