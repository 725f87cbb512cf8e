// The Bode section of the study (docs/linearization.md §6–7): per operating point, the
// linearised Saint-Venant pool's frequency response (gate → y_dwe) over the PRBS band beside
// those of the LIOM and LFOM fitted to the recording in the time domain, and one computed
// sentence saying whether the pool is fractional in that band. `canalsim reproduce` writes it as
// bode.md, bode.json and bode.html next to the tables (which stay as they were).
#pragma once

#include <complex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "linearize/fractional_fit.hpp"
#include "plot/figure.hpp"
#include "scenarios/scenario.hpp"
#include "study/study.hpp"

namespace canalsim::study {

struct BodeSection {
  std::string experiment;
  double operating_opening_mm = 0.0;
  linearize::Band band;
  std::vector<double> omega;                      // 200 log-spaced points of the band [rad/s]
  std::vector<std::complex<double>> pde, liom, lfom;  // mm/mm
  double liom_error = 0.0, lfom_error = 0.0;      // rms relative complex error against the PDE
  double fitted_lfom_lambda = 1.0;                // λ of the time-domain LFOM fit
  double gain_change_db = 0.0;                    // PDE gain at the band's top over its bottom
  linearize::FractionalFit pde_fit;               // the LFOM fitted to the PDE in the band
  std::string sentence;
};

// One section per experiment fitted in both the LIOM and the LFOM tables of `result`, the pool
// linearised from `scenario` (the one the recordings were simulated from).
std::vector<BodeSection> bode_sections(const scenarios::Scenario& scenario, const StudyResult& result);

// "fractional in the band" when the LFOM fitted to the PDE is within 10 % with λ < 0.9 and at
// most 0.7 of the λ = 1 fit's error; "not a first-order lag" when no λ gets within 10 %; else
// "first order".
std::string fractionality_sentence(const BodeSection& section);

nlohmann::json bode_json(const std::vector<BodeSection>& sections);
std::string bode_markdown(const std::vector<BodeSection>& sections);
// Per operating point a Bode plot (gain in dB above phase in degrees, against ω on a log axis) of
// the PDE, the LIOM and the LFOM, named bode_EXPERIMENT for its standalone file.
std::vector<plot::Figure> bode_figures(const std::vector<BodeSection>& sections);
// A self-contained page: per operating point its sentence and its bode_figures plot, inline SVG
// (no script).
std::string bode_html(const std::vector<BodeSection>& sections);
// The same content as a section of another page (report.html's Bode section), under a heading
// `title_tag` with one `point_tag` heading per operating point.
std::string bode_html_section(const std::vector<BodeSection>& sections, const std::string& title_tag = "h2",
                              const std::string& point_tag = "h3");

}  // namespace canalsim::study
