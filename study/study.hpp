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
// The study needs only recordings and the reduced models (docs/architecture.md); the CLI
// (cli/reproduce.cpp) simulates the laboratory canal and passes the recordings in. Its parts:
// study/paper.hpp (the published tables), study/claims.hpp (the conclusions, computed),
// study/render.hpp (tables.json, tables.md, report.html).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "core/recording.hpp"
#include "core/status.hpp"
#include "reduced_models/identification.hpp"
#include "study/claims.hpp"

namespace canalsim::study {

using reduced::ExperimentData;
using reduced::FitResult;
using reduced::GammaGrid;
using reduced::GammaSweep;
using reduced::Model;
using reduced::ModelKind;
using reduced::Validation;

// ---------------------------------------------------------------------------------------------
// Options and results.

struct StudyOptions {
  GammaGrid gamma{0.0, 10.0, 0.05};  // the paper's search range [0, 10]
  unsigned threads = 2;              // FitOptions.threads for every fit and sweep
  // Progress of the fits and sweeps (may be empty).
  ProgressCallback progress;
  // PRBS design of the experiments (for the spectrum of Figure 4): clock period Tc and stages n.
  double prbs_clock_s = 0.5;
  int prbs_stages = 9;
  // Samples kept per plotted series in report.html (every k-th sample); 0 = all.
  std::size_t plot_points = 1200;

  Status validate() const;  // ok, or one line naming the field
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

}  // namespace canalsim::study
