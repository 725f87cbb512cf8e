// Diagnosis output: the JSON document (verdict, effects, mismatch, channels, thresholds) and a
// self-contained HTML page (inline SVG, no scripts fetched from anywhere).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "diagnosis/diagnose.hpp"
#include "plot/figure.hpp"

namespace canalsim::diagnosis {

// verdict, reason, effects (ranked: name, score, parameters, nrmse_before, nrmse_after,
// heldout_nrmse_before, heldout_nrmse_after, ...), mismatch (windows, band_hz, by_recording,
// by_regime, by_event, by_level, by_channel), mismatch_after, residual_tests (before/after),
// noise figures. Series are left out (they are in the HTML report).
nlohmann::json to_json(const Diagnosis& diagnosis);

// The report's figures, each named for its standalone file (RECORDING_levels_and_residual,
// RECORDING_residual_autocorrelation, RECORDING_step_zoom): per recording the recorded primary level
// against the nominal and the corrected model with the residuals [mm] below (the mismatch windows
// shaded when the verdict is not `none`), the residuals' autocorrelation with the 95 % band, and the
// response to the largest command change.
std::vector<plot::Figure> report_figures(const Diagnosis& diagnosis);

// One HTML page: verdict, ranked table, where the mismatch lives, and report_figures inline.
std::string html_report(const Diagnosis& diagnosis, const std::string& title);

// A text summary for the terminal (verdict, ranked table, location).
std::string text_summary(const Diagnosis& diagnosis);

}  // namespace canalsim::diagnosis
