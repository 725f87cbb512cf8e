// The study's outputs: tables.json, tables.md and a self-contained report.html.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "plot/figure.hpp"
#include "study/study.hpp"

namespace canalsim::study {

// Outputs: tables.json, tables.md and a self-contained report.html (figures inline as SVG; no
// script, no network).
nlohmann::json to_json(const StudyResult& result);
std::string to_markdown(const StudyResult& result);
// report.html's figures, each named for its standalone file: responses_OP and validation_OP (one
// panel per model), gamma_MODEL, flow_regime_OP and prbs_spectrum.
std::vector<plot::Figure> report_figures(const StudyResult& result, const std::map<std::string, Recording>& recordings,
                                         const StudyOptions& options = {});
// `extra_section`: HTML placed after the figures (reproduce passes the Bode section, study/bode.hpp).
std::string to_html(const StudyResult& result, const std::map<std::string, Recording>& recordings,
                    const StudyOptions& options = {}, const std::string& extra_section = "");

}  // namespace canalsim::study
