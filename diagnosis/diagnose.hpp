// Diagnosis of a scenario model against recordings: compare, locate, explain, refit.
//
//   1. Nominal: each recording is replayed through the scenario (its gate command u_mm drives the
//      controlled gate) with ideal sensors; the scenario's own sensor model (resolution, delay,
//      offset) is applied to the sampled true levels. Residuals = recording − model per channel.
//   2. Locate (locate.hpp) and test the residuals (residual_tests.hpp).
//   3. Explain: every catalog effect (catalog.hpp; an instrument's fault on each level channel the
//      recordings carry) is fitted, one parameter each, on the first
//      `fit_fraction` of every recording and judged on the rest. Cost = Σ_channels w_c·MSE_c with
//      w_c = 1/s_c², s_c the within-recording spread of the channel (floored), so that levels,
//      gate position and flow all count. Score = relative reduction of the held-out cost.
//      The score is judged on a channel-balanced cost (mean over channels of MSE_c relative to
//      the nominal model's), so an effect that explains one channel fully counts.
//      An effect is *significant* when its score ≥ min_score, its BIC on the fitted part improves
//      by at least min_bic_gain (with the number of samples corrected for residual correlation),
//      its parameter is material (catalog.hpp) and its held-out fit improves (pipeline.hpp).
//   4. Verdict: the best significant effect; else `none` when every level channel's nominal
//      residual is within its noise or what the calibration left on it; else `unexplained`,
//      located, with a discrepancy model (pipeline.hpp).
//   5. Refit: the winner's parameter with a standard deviation (curvature of the cost, inflated
//      by residual correlation), Nrmse before/after on fitted and held-out parts, residual tests
//      after.
#pragma once

#include <functional>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "calibration/replay.hpp"
#include "diagnosis/catalog.hpp"
#include "diagnosis/pipeline.hpp"
#include "diagnosis/locate.hpp"
#include "diagnosis/residual_tests.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::diagnosis {

struct DiagnoseOptions {
  double fit_fraction = 0.5;     // leading share of each recording used for fitting; (0.1, 0.9)
  // Channels compared (those a recording lacks are skipped); the primary must be present.
  std::vector<std::string> channels = {"y_dwe_mm", "y_dw_mm", "y_up_mm", "x_up_mm", "q_lps"};
  std::string primary = "y_dwe_mm";  // Nrmse (eq. 19) and location are reported on this channel
  std::vector<std::string> candidates;  // effect names; empty = the whole catalog
  double min_score = 0.15;       // held-out cost reduction for significance; (0, 1)
  // The held-out cost reduction an effect must add to an explanation that already has a
  // significant verdict (pipeline step 5), relative to the explanation without it; (0, min_score].
  // Lower than min_score: the verdict has shown that the canal changed, and a second effect is
  // judged on what the first leaves, with the BIC gain and the rising held-out Nrmse still
  // required. A leak beside a discharge coefficient that is 11 % off removed 5.5 % of what the
  // coefficient left (BIC −233) and was dropped at 0.15 (docs/diagnosis.md).
  double added_min_score = 0.05;
  // Step 5 skips the joint fit of a candidate whose first-order prospect, trusted, stays below
  // half of added_min_score, unless it may be an ambiguous pair with the verdict
  // (docs/diagnosis.md, "Several effects"). false: every candidate is fitted jointly (slower; the
  // same explanation).
  bool screen_joint_fits = true;
  // Step 2 stops the search of a re-simulated candidate at its probe when the first-order
  // prospect from the probe, trusted, stays below half of min_score in total and slower than the
  // fast band (docs/diagnosis.md §4, the secant search). false: every candidate is searched to
  // its best point (slower; the same verdict).
  bool screen_single_fits = true;
  // A search (a re-simulated effect's secant or scan, a joint fit's Levenberg–Marquardt) compares
  // its points by the fitted-part residual alone, and the solver is causal: its replays stop after
  // the fitted part (and the lookahead a negative reading delay needs), and only the point it
  // returns is replayed whole. false: every replay runs the whole recording (slower; the same
  // result).
  bool search_fitted_part_only = true;
  // A search's replays (and a secant's probe) run on the scenario's grid halved until all its
  // pools together have at most this many cells, each replay corrected by the nominal model's
  // difference between the two grids (defect correction): a replay costs the cells squared, and
  // what a grid adds to the levels hardly changes with a small change of the canal. Every point
  // that can be significant is judged on the scenario's grid (docs/diagnosis.md §4). Twice the
  // lab's own 100 cells. 0: every replay on the scenario's grid.
  int search_max_cells = 200;    // >= 0
  double min_bic_gain = 10.0;    // BIC improvement on the fitted part; >= 0
  double none_noise_factor = 3.0;  // "within the noise": primary RMS <= this × noise; > 0
  int max_evaluations = 6;       // simulations per re-simulated candidate (secant steps); 2..50
  int threads = 2;               // recordings simulated in parallel; >= 1
  // Replay the recorded y_up_mm as the upstream level. Off by default: a level-sensor fault
  // (offset, delay) would then enter the hydraulics and blur its own signature.
  bool use_recorded_upstream = false;
  // The recorded command changed somewhere in the sample interval before it shows; the replay
  // switches half a sample earlier so that, on average, it is not late (0 = at the sample).
  double command_lead_samples = 0.5;  // [0, 1]
  // A clocked command (a PRBS) switches on a grid t0 + m T; when one period and phase are
  // consistent with every sampled change, the replay switches at the reconstructed instants
  // instead (command_switch_times), which removes the sampling jitter of the input.
  bool reconstruct_clock = true;
  double settle_time_s = 600.0;  // SimulateOptions::settle_time; >= 0
  // Leading seconds of every recording left out of costs, tests and location. None by default:
  // the replay starts from the steady state of the recording's own initial state (its
  // operating_opening_mm metadata or first command; with use_recorded_upstream also its first
  // upstream level), so every sample after it is comparable (10 s would be a fifth of a short
  // step test). At most a third of a recording is dropped.
  double warmup_s = 0.0;         // >= 0
  // What a calibration of the scenario left open (docs/calibration.md): calibration parameter name
  // (cd_free, cd_submerged, manning_n, downstream_opening_mm, offset_mm, offset_y_dwe_mm, ...) →
  // one standard deviation in its unit. An effect that moves a calibrated parameter is material
  // only beyond `calibrated_z` of these standard deviations: material only where it exceeds what
  // the calibration leaves open. A calibrated scenario's [calibration.std_alone] (else
  // [calibration.std]) fills it. Empty for an uncalibrated scenario.
  std::map<std::string, double> calibrated_std;
  double calibrated_z = 3.0;     // > 0
  // Primary-channel residual RMS the calibration left on its own baseline recordings [mm] (0 =
  // not calibrated). A model calibrated on a canal still differs from it by this much in the
  // ordinary course (model form: grid, gate law); a residual within baseline_factor times it is
  // not a change of the canal, and the verdict is `none` when no effect is significant.
  double baseline_rms_mm = 0.0;  // >= 0
  // The same for each level channel (0 or missing: baseline_rms_mm stands for it).
  std::map<std::string, double> baseline_rms_by_channel;
  // The part of each level channel's baseline residual slower than 2 s
  // (calibration::slower_than_fast_band; missing: that channel's residual is judged in total
  // only). A model's error from resolving bores is fast; an effect as large as it in total can
  // still stand far beyond it in the slower part, where the model's error is a few times smaller.
  std::map<std::string, double> baseline_slow_rms_by_channel;
  // √2: the RMS of the model's own error b and an effect as large as it, uncorrelated,
  // sqrt(b² + b²). A residual below it leaves room only for an effect smaller than the model's
  // error on clean recordings, which these recordings cannot tell from that error; beyond it an
  // effect at least as large as the model's error is there, named or not.
  double baseline_factor = std::numbers::sqrt2;  // > 0
  ResidualTestOptions tests;
  LocateOptions locate;
  ProgressCallback progress;  // share of the simulations done, and the stage

  Status validate() const;
};

// Re-exported from the replay machinery (calibration/replay.hpp): the reconstructed switching
// instants of a clocked command, and the problems that make recordings unusable with a scenario.
using calibration::command_switch_times;
using calibration::check_recordings;

// The replay of the recordings the diagnosis uses (calibration/replay.hpp). A calibration whose
// scenario is then diagnosed must replay the same way (fit_fraction 1): a baseline calibrated with
// the recorded upstream level, say, and diagnosed with the upstream model would leave the
// difference — an offset of the upstream sensor turned into a discharge coefficient — as a
// spurious effect.
calibration::ReplayOptions diagnosis_replay(const DiagnoseOptions& options);

// The replay `canalsim calibrate` uses by default (`--replay diagnosis`): the diagnosis' drive
// (the upstream model drives the head gate), every sample fitted, the calibration's channels —
// so that the scenario it writes can be diagnosed next.
calibration::ReplayOptions calibration_replay_for_diagnosis();

// Runs the diagnosis. Recordings in declared units (u_unit / u_scale_mm_per_unit, y_unit /
// y_scale_mm_per_unit; docs/recording-format.md) are converted to millimetres first. Without
// options.calibrated_std (baseline_rms_mm), the scenario's own [calibration.std] table
// ([calibration] baseline_rms_mm) — a file written by `canalsim calibrate` — fills it. Throws
// InputError (all problems of check_recordings, a bad declared unit, an unknown calibrated
// parameter, or invalid options); a simulation failure is returned as ok = false with the message.
Diagnosis diagnose(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings,
                   const DiagnoseOptions& options = {});

}  // namespace canalsim::diagnosis
