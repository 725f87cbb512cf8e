// A calibration for people and programs: the terminal table, the JSON document and the
// self-contained HTML report (inline SVG, opens offline).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "calibration/calibrate.hpp"
#include "plot/figure.hpp"

namespace canalsim::calibration {

// Parameter, start, estimate ± std, bounds; identifiability; RMS/Nrmse per recording and
// channel before and after; the grid check; simulations and time.
std::string text_summary(const Calibration& c);
nlohmann::json to_json(const Calibration& c);
// The gate laws compared (CalibrateOptions::gate_laws), one line each, the kept one marked.
std::string gate_law_lines(const Calibration& c);
// The model-form choices refitted (CalibrateOptions::try_model_forms), one line each with the
// verdict; empty when none were.
std::string model_form_lines(const Calibration& c);
// Where the level residual lives (residual_breakdown.hpp), a line per group: with the model-form
// choices' shares when they were refitted, else the calibration's own; empty without level channels.
std::string breakdown_lines(const Calibration& c);
// The grids calibrated on (CalibrateOptions::grid_refinements) and why the refinement stopped;
// empty when none was asked for.
std::string grid_lines(const Calibration& c);
// The report's figures, each named for its standalone file (RECORDING_CHANNEL_levels_and_residual,
// …_residual_autocorrelation, …_step_zoom, …_residual_spectrum): per recording and level channel the
// recorded level against the nominal and the calibrated scenario with the residuals [mm] below, the
// residuals' autocorrelation with the 95 % band, the response to the largest command change and the
// residuals' amplitude spectra.
std::vector<plot::Figure> report_figures(const Calibration& c);
std::string html_report(const Calibration& c, const std::string& title);

}  // namespace canalsim::calibration
