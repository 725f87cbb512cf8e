// The paper's study (Gharab, Feliu-Batlle & Rivas-Perez 2019, Sections 5–7, Tables 1–8, Figures
// 4, 6, 8, 10) repeated on recordings — in `canalsim reproduce`, recordings of the simulated
// laboratory canal — and compared with the published numbers.
//
//   Table 1  LIOM    fits at op1–op4, nominal model (IAE_c, eq. 21), uncertainty index Δp (eq. 22)
//   Table 2  LFOM    the same
//   Table 3  NLIOM-S fits at op1–op2 (submerged flow), γ by the best Nrmse over a grid (Fig. 8)
//   Table 4  NLFOM-S the same
//   Table 5  validation of the four nominal models at op1*, op2* (Nrmse, eq. 19)
//   Table 6  NLIOM-F fits at op3–op4 (free flow), γ sweep (Fig. 10)
//   Table 7  NLFOM-F the same
//   Table 8  validation of LIOM, LFOM, NLIOM-F, NLFOM-F nominal models at op3*, op4*
//
// Deviations are taken from each experiment's operating point: the gate opening the canal was
// settled at (recording metadata `operating_opening_mm`), not the first command sample (a PRBS
// starts at op ± amplitude). The output operating point is the mean level before u first changes.
//
// Every conclusion of the paper checked here is a Claim: a sentence built from the paper's and
// our numbers, saying whether the conclusion holds on these recordings. No verdict is written by
// hand; each one is computed.
//
// This module needs only recordings (DESIGN.md: reduced_models depends on the recording type);
// the CLI (cli/reproduce.cpp) simulates the laboratory canal and passes the recordings in.
#pragma once

#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "reduced_models/identification.hpp"

namespace canalsim::reduced::study {

// ---------------------------------------------------------------------------------------------
// The paper's tables (reduced_models/data/paper_tables.json, embedded at configure time).

const nlohmann::json& paper_tables();
// The number at a JSON pointer, e.g. "/table1_LIOM/fits/op1/K"; throws std::out_of_range naming
// the pointer when it is absent or not a number.
double paper_value(const std::string& pointer);

// ---------------------------------------------------------------------------------------------
// Generated conclusions.

struct Claim {
  std::string table;  // "table4"
  std::string text;   // the whole sentence, ending with its verdict
  bool holds = false;
};

// "SUBJECT at op1 and op2: paper +3.13 and +5.91 UNIT, here +2.10 and −0.40 UNIT — holds." The
// claim is that every difference is positive; it holds when every `here` difference is positive
// at the printed precision (≥ 0.005; the verdict names the places where it fails). Sizes of `where`, `paper` and `here` must match.
Claim difference_claim(const std::string& table, const std::string& subject,
                       const std::vector<std::string>& where, const std::vector<double>& paper,
                       const std::vector<double>& here, const std::string& unit = "points");

// "SUBJECT (RANGE_TEXT) at op3 and op4: paper 6.15 and 6.85, here 1.2 and 0.8 — does not hold
// (op3, op4)." Holds when every `here` value lies in [lower, upper].
Claim range_claim(const std::string& table, const std::string& subject, const std::string& range_text,
                  const std::vector<std::string>& where, const std::vector<double>& paper,
                  const std::vector<double>& here, double lower, double upper);

// "SUBJECT: paper BEST_PAPER, here BEST_HERE — holds." for "which model is best" claims; holds
// when the names are equal.
Claim same_claim(const std::string& table, const std::string& subject, const std::string& paper,
                 const std::string& here);

// ---------------------------------------------------------------------------------------------
// Options and results.

struct StudyOptions {
  GammaGrid gamma{0.0, 10.0, 0.05};  // the paper's search range [0, 10]
  unsigned threads = 2;              // FitOptions.threads for every fit and sweep
  // Called with one-line progress messages (may be empty).
  std::function<void(const std::string&)> progress;
  // PRBS design of the experiments (for the spectrum of Figure 4): clock period Tc and stages n.
  double prbs_clock_s = 0.5;
  int prbs_stages = 9;
  // Samples kept per plotted series in report.html (every k-th sample); 0 = all.
  std::size_t plot_points = 1200;

  std::string validate() const;  // empty when valid, else one line naming the field
};

// Experiments the study needs and what they stand for in the paper.
struct ExperimentRoles {
  std::vector<std::string> fit_all{"op1", "op2", "op3", "op4"};
  std::vector<std::string> submerged{"op1", "op2"};
  std::vector<std::string> free{"op3", "op4"};
  std::vector<std::string> submerged_validation{"op1*", "op2*"};
  std::vector<std::string> free_validation{"op3b", "op4b"};  // the paper's op3*, op4*
  std::vector<std::string> submerged_validation_paper{"op1*", "op2*"};
  std::vector<std::string> free_validation_paper{"op3*", "op4*"};
  std::vector<std::string> all() const;  // every name above, once, in order
};

// One model table (Tables 1, 2, 3, 4, 6, 7).
struct TableSpec {
  std::string id;         // "table3"
  std::string paper_key;  // "table3_NLIOM_S"
  std::string title;
  ModelKind kind = ModelKind::liom;
  std::vector<std::string> experiments;
};

struct ModelTable {
  TableSpec spec;
  std::vector<FitResult> fits;       // one per experiment (γ models: the best of the sweep)
  std::vector<GammaSweep> sweeps;    // γ models: one per experiment
  FitResult nominal;                 // one model for all experiments (IAE_c, eq. 21)
  std::optional<GammaSweep> nominal_sweep;
  std::map<std::string, double> uncertainty;  // Δp (eq. 22) as a fraction
};

struct ValidationTable {
  std::string id;                                  // "table5"
  std::string paper_key;                           // "table5_validation_submerged"
  std::string title;
  std::vector<std::string> experiments;            // ours
  std::vector<std::string> paper_experiments;      // the paper's names (op1*, …)
  std::vector<std::string> models;                 // "LIOM", "LFOM", "NLIOM-S", "NLFOM-S"
  std::vector<std::vector<Validation>> results;    // [experiment][model]
};

struct RegimeSummary {
  std::string experiment;
  double operating_opening_mm = 0.0;
  double free_fraction = 0.0;     // share of samples in free flow (condition 8)
  double min_margin_mm = 0.0;     // min over t of y_up − y_lc (> 0: always free)
  double max_margin_mm = 0.0;     // max over t of y_up − y_lc (< 0: always submerged)
};

struct Spectrum {
  std::vector<double> omega;      // rad/s, the PRBS line frequencies 2πk/(N Tc)
  std::vector<double> magnitude;  // |X(ω)| of the unit-amplitude PRBS over one period
  std::vector<double> envelope;   // Tc √(N+1) |sinc(ω Tc / 2π)|
  std::vector<double> step;       // |1/(jω)| of a unit step, for comparison (paper Fig. 4)
  double bandwidth_design_rad_s = 0.0;    // half-power point of the envelope
  double bandwidth_measured_rad_s = 0.0;  // where the smoothed lines fall below max/√2
  std::string experiment;
};

struct StudyResult {
  std::vector<ModelTable> tables;  // tables 1, 2, 3, 4, 6, 7 in that order
  ValidationTable table5, table8;
  std::vector<RegimeSummary> regimes;
  Spectrum spectrum;
  std::vector<Claim> claims;
  GammaGrid gamma;
  double seconds = 0.0;  // wall time of run_study
};

// Prepares an experiment: deviations from the recording's operating point (metadata
// `operating_opening_mm` when present, else u(0)).
ExperimentData study_data(const Recording& recording);

// Fits one model table on prepared data (`data` must hold every experiment of `spec`).
ModelTable build_model_table(const TableSpec& spec, const std::map<std::string, ExperimentData>& data,
                             const StudyOptions& options);

// The whole study. `recordings` maps experiment names to recordings and must hold every name of
// `roles`; throws InputError naming a missing experiment.
StudyResult run_study(const std::map<std::string, Recording>& recordings,
                      const StudyOptions& options = {}, const ExperimentRoles& roles = {});

// The claims about one model table or the validation tables (used by run_study; exposed for tests).
std::vector<Claim> conclusions(const StudyResult& result);

// Outputs: tables.json, tables.md and a self-contained report.html (data and plotting code
// inline; no network).
nlohmann::json to_json(const StudyResult& result);
std::string to_markdown(const StudyResult& result);
std::string to_html(const StudyResult& result, const std::map<std::string, Recording>& recordings,
                    const StudyOptions& options = {});

}  // namespace canalsim::reduced::study
