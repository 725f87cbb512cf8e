// Diagnosis against a calibrated baseline: the workflow of a canal operator, who
// calibrates the scenario once on clean baseline recordings and then diagnoses later recordings
// against the calibrated scenario.
//
//   1. Check: baseline and recordings must be of the same canal and logger — one sampling period,
//      the same `scenario` metadata where both carry it — and usable with the scenario
//      (check_recordings). A problem is one InputError line naming the file and the difference.
//   2. Calibrate the scenario on the baseline (calibration::calibrate, docs/calibration.md): the
//      default parameter set (the laboratory's unknowns), replayed the way the diagnosis replays
//      (the same upstream drive and command timing), without the grid check unless asked.
//   3. Diagnose the recordings against the calibrated scenario (diagnose.hpp) with
//      DiagnoseOptions::calibrated_std filled from the calibration's standard deviations (an
//      effect that moves a calibrated parameter is material only beyond what the calibration
//      left open) and baseline_rms_mm from its residual on the baseline (a residual within a few
//      times it is the model's ordinary difference from the canal).
//
//   BaselineOptions o;
//   const BaselineDiagnosis r = diagnose_with_baseline(scenario, baseline, recordings, o);
//   r.calibration.parameters   // calibrated values ± std
//   r.diagnosis.verdict
//
// Recordings in declared units (u_unit / u_scale_mm_per_unit, y_unit / y_scale_mm_per_unit;
// docs/recording-format.md) are converted to millimetres first.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "calibration/calibrate.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"
#include "core/status.hpp"
#include "diagnosis/diagnose.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::diagnosis {

struct BaselineOptions {
  // The diagnosis of the recordings; its calibrated_std is replaced by the calibration's and its
  // progress by the one below.
  DiagnoseOptions diagnosis;
  // Calibration parameter specs (NAME or NAME:LOW:HIGH); empty = calibration's default set.
  std::vector<std::string> parameters;
  int calibration_starts = 1;      // Levenberg–Marquardt runs; 1..10 (the scenario's values first)
  // Levenberg–Marquardt iterations per run; 1..500. calibrate's 30: with the diagnosis' replay,
  // 10 left the cost 29 % above the one after 30 on four 255.5 s laboratory baselines of an
  // independent truth, and the calibration takes 7.3 s with 30 (bench/README.md, "Diagnosis").
  int calibration_iterations = 30;
  bool grid_check = false;         // re-simulate the calibrated optimum on twice the cells
  ProgressCallback progress;       // calibration, then diagnosis, as one share
  Status validate() const;
};

struct BaselineDiagnosis {
  calibration::Calibration calibration;   // of the baseline; its series are left empty
  Diagnosis diagnosis;                     // of the recordings against calibration.calibrated
  std::vector<std::string> baseline;       // the baseline recordings' names (their source)
};

// What a calibration leaves open for a diagnosis against the calibrated model: the statistical
// standard deviation of the estimate (how well the baseline determines it), not its numerical
// part. The grid shift says how far the value is from the physical parameter, an error that the
// calibrated model and the diagnosis, on the same grid, share: it is no room for a change of the
// canal. So `diagnose --scenario cal.toml` judges materiality as `diagnose --baseline` does (whose
// calibration runs without the grid check). +inf when the data do not determine it.
double left_open(const calibration::ParameterEstimate& estimate);

// What a calibration left open, for DiagnoseOptions::calibrated_std: parameter name → left_open,
// for every parameter the data determined (finite).
std::map<std::string, double> calibrated_std_of(const calibration::Calibration& calibration);

// The same with the other parameters held at their estimates: σ_i / sqrt((R⁻¹)_ii), R the
// correlation matrix. A diagnosis fits one effect with the calibrated parameters fixed, so this,
// not the marginal deviation a correlated neighbour inflates (an offset traded against the
// downstream opening), is the calibration's own tolerance for it. The marginal deviations when R
// is not positive definite.
std::map<std::string, double> calibrated_std_alone_of(const calibration::Calibration& calibration);

// What the calibration left on its own baseline, for DiagnoseOptions::baseline_rms_mm: the RMS of
// the primary channel's residual after calibration over the baseline recordings [mm].
double baseline_rms_of(const calibration::Calibration& calibration, const std::string& primary);
// The same for every level channel it fitted (DiagnoseOptions::baseline_rms_by_channel).
std::map<std::string, double> baseline_rms_by_channel(const calibration::Calibration& calibration);
// The RMS of that residual's part slower than the fast band (calibration::slower_than_fast_band),
// per level channel (DiagnoseOptions::baseline_slow_rms_by_channel): from the calibration's
// series, so empty once they are cleared.
std::map<std::string, double> baseline_slow_rms_by_channel(const calibration::Calibration& calibration);

// The calibrated standard deviations a scenario file carries, written by `canalsim calibrate`:
// [calibration.std_alone] when it has one, else [calibration.std]; each name checked against the
// scenario's calibration parameters.
// Throws InputError naming the file and the unknown name.
std::map<std::string, double> calibrated_std_of(const scenarios::Scenario& scenario);

// Problems that make baseline and recordings incomparable, one line each naming the baseline
// file: a sampling period other than the recordings' ("base3.csv: sampled every 0.26 s, the
// recordings every 0.13 s"), another canal by the `scenario` metadata. Recordings of different
// periods among themselves are named too. Empty when they match.
std::vector<std::string> check_baseline(const std::vector<Recording>& baseline, const std::vector<Recording>& recordings);

// The calibration part of a result for people and programs: a short table (parameter, value ±
// std, start, unit; the weighted residual before and after) and the JSON object `baseline`
// (docs/diagnosis.md: files, parameters with value, std — null when not determined —, start,
// unit and at_bound, residual_before/after, fits per recording and channel, simulations, seconds).
std::string baseline_summary(const BaselineDiagnosis& result);
nlohmann::json baseline_json(const BaselineDiagnosis& result);

// Where the calibration may not hold, one warning line per recording: its gate command leaves
// the span the baseline's commands covered by more than 2 mm ("rec3.csv: gate command 38..48 mm,
// the baseline covered 10..20 mm: the calibration may not hold there") — a coefficient of the
// free-flow law is not determined by a baseline that never ran free. Empty when covered.
std::vector<std::string> baseline_coverage(const std::vector<Recording>& baseline, const std::vector<Recording>& recordings);

// Step 2's options: the calibration of the baseline replayed exactly as the diagnosis replays
// (diagnosis_replay, diagnose.hpp; every sample fitted), as the realistic blind test calibrates:
// what the calibration fits is then the model the diagnosis compares with.
calibration::CalibrateOptions baseline_calibration_options(const BaselineOptions& options);

// Step 3's options: `diagnosis` with what `calibration` left open (calibrated_std_alone_of) and
// what it left on its baseline, in total and slower than the fast band. Needs the calibration's
// series (baseline_slow_rms_by_channel).
DiagnoseOptions against_calibration(const calibration::Calibration& calibration, DiagnoseOptions diagnosis);

// Runs the three steps. Throws InputError (incompatible or unusable recordings, bad options);
// a calibration that fails numerically is returned with diagnosis.ok = false and its message.
BaselineDiagnosis diagnose_with_baseline(const scenarios::Scenario& scenario, const std::vector<Recording>& baseline,
                                         const std::vector<Recording>& recordings, const BaselineOptions& options = {});

}  // namespace canalsim::diagnosis
