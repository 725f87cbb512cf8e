// A calibration for people and programs: the terminal table, the JSON document and the
// self-contained HTML report (inline SVG, opens offline).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "calibration/calibrate.hpp"

namespace canalsim::calibration {

// Parameter, start, estimate ± std, bounds; identifiability; RMS/Nrmse per recording and
// channel before and after; the grid check; simulations and time.
std::string text_summary(const Calibration& c);
nlohmann::json to_json(const Calibration& c);
// The gate laws compared (CalibrateOptions::gate_laws), one line each, the kept one marked.
std::string gate_law_lines(const Calibration& c);
// The grids calibrated on (CalibrateOptions::grid_refinements) and why the refinement stopped;
// empty when none was asked for.
std::string grid_lines(const Calibration& c);
std::string html_report(const Calibration& c, const std::string& title);

}  // namespace canalsim::calibration
