// The study's outputs: tables.json, tables.md and a self-contained report.html.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "study/study.hpp"

namespace canalsim::study {

// Outputs: tables.json, tables.md and a self-contained report.html (data and plotting code
// inline; no network).
nlohmann::json to_json(const StudyResult& result);
std::string to_markdown(const StudyResult& result);
// `extra_section`: HTML placed after the figures (reproduce passes the Bode section, study/bode.hpp).
std::string to_html(const StudyResult& result, const std::map<std::string, Recording>& recordings,
                    const StudyOptions& options = {}, const std::string& extra_section = "");

}  // namespace canalsim::study
