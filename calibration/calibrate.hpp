// Calibration: the scenario parameters (calibration/parameters.hpp) that make the simulator
// reproduce recordings it did not make.
//
//   1. Every recording is replayed (calibration/replay.hpp): its command drives the controlled
//      gate, its recorded upstream level feeds the head gate where it has one, and it starts from
//      the steady state at its own first samples.
//   2. Weighted nonlinear least squares: r = sqrt(w_c) (recorded − model) over every recording,
//      channel and sample, w_c = 1 / s_c² with s_c the channel's within-recording spread (as the
//      diagnosis weighs channels). Level predictions are the model's levels through the sensors'
//      offsets and delay, unrounded: the mean-square-best prediction of a quantised reading whose
//      input wanders over more than a step.
//   3. Ceres Solver's bounded Levenberg–Marquardt in the search coordinates (log for roughness and
//      coefficients), Jacobians by forward differences whose perturbed simulations run in
//      parallel (core/parallel.hpp); sensor-only parameters re-observe one simulation instead.
//      Several starts — the scenario's values and the best of points spread over the bounds —
//      the best kept; a further start scouts with a loose tolerance and is continued only when it
//      leads below the best so far.
//   4. Statistics as PEST and parmest give them: covariance s² (JᵀJ)⁻¹ inflated by N / N_eff for
//      residual autocorrelation (integrated autocorrelation time per series), standard deviations, correlations, composite
//      scaled sensitivities, identifiability in words, fit per recording and channel before and
//      after, on the fitted and the validation recordings, and the grid check (the residual on a
//      grid with twice the cells at the optimum).
//   5. The numerical uncertainty (calibration/discretisation.hpp): the optimum re-estimated on
//      twice the cells, the other limiter and half the Courant number; added to the std. The
//      re-estimate on twice the cells, extrapolated, gives the grid-converged estimates.
#pragma once

#include <string>
#include <vector>

#include "calibration/discretisation.hpp"
#include "calibration/model_form.hpp"
#include "calibration/parameters.hpp"
#include "calibration/replay.hpp"
#include "calibration/residual_breakdown.hpp"
#include "core/progress.hpp"
#include "core/recording.hpp"
#include "core/status.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

struct CalibrateOptions {
  // Parameter specs, NAME or NAME:LOW:HIGH; empty = default_parameters(); every one +NAME or
  // +NAME:LOW:HIGH = the default set and those (chosen_parameters).
  std::vector<std::string> parameters;
  // The replay: recorded upstream level on, every sample after the initial state compared, and
  // each recording started from the steady state at its own first level.
  ReplayOptions replay = default_replay();
  int starts = 2;            // Levenberg–Marquardt runs at most (the scenario's values first); 1..10
  // Run the further starts only when the first optimum is doubtful: not converged, at a bound,
  // a weighted cost per sample above 0.05, a parameter not determined or with a relative std
  // above 50 % (Calibration::starts_note says which). Off: always run them.
  bool further_starts_only_when_doubtful = true;
  int screened_points = 6;   // points spread over the bounds whose cost picks the other starts; >= 0
  int max_iterations = 30;   // per run; 1..500
  int threads = 2;           // simulations in parallel; 1..64
  // The grid check and the numerical uncertainty: re-estimate the optimum on other numerics
  // (discretisation.hpp; 6 simulations per recording, two of them on twice the cells).
  bool grid_check = true;
  // Gate laws to compare: each is put at every sluice gate of the scenario
  // (scenarios/variation.hpp with_gate_law) and calibrated in turn, and the one with the lowest
  // weighted cost is kept — whether the recordings follow Swamee's law or the paper's simpler
  // eqs. 9/11. Empty (the default): the scenario's own laws, one calibration.
  std::vector<scenarios::GateLaw> gate_laws;
  // Grid refinement: while the grid check finds that twice the cells lower the weighted cost by
  // more than a third (the discretisation, not the physics, limits the fit), or the last
  // refinement lowered the fitted cost by more than a third, calibrate again on twice the cells
  // of every pool, from the estimates, at most this many times (0..3); a refinement that does not
  // lower the cost is dropped. Each
  // doubling costs about 2.6 times the simulations' time (lab: 100 -> 200 cells). 0 (the
  // library's default): the scenario's grid; `canalsim calibrate` refines twice at most.
  int grid_refinements = 0;
  // The model written (written_model.hpp): with the grid check, when the grid-converged estimates
  // on twice (or, while the grid still limits them, four times) the last grid's cells fit the
  // recordings better than the estimates, calibrated holds them (and that grid). false (the library's default): the estimates on the last grid;
  // `canalsim calibrate` turns it on.
  bool write_grid_converged = false;
  // After the calibration, each model-form choice left open added in turn and refitted from the
  // estimates (model_form.hpp): about one calibration from the estimates per choice. Off by
  // default; `canalsim calibrate --model-forms`.
  bool try_model_forms = false;
  ProgressCallback progress;
  [[nodiscard]] Status validate() const;  // ok, or one line naming the field (core/status.hpp)
  static ReplayOptions default_replay();
};

struct ParameterEstimate {
  std::string name, unit, key;
  double key_scale = 1.0;
  double start = 0.0, value = 0.0;
  // One standard deviation, +inf when the data do not determine it: the statistical one and the
  // numerical one (`grid_shift`: how far the estimate moves on other numerics — twice the cells
  // counted twice, the other limiter, half the Courant number — in quadrature; 0 without the
  // grid check) combined in quadrature.
  double std = 0.0;
  double statistical_std = 0.0, grid_shift = 0.0;
  // The grid-converged estimate (discretisation.hpp grid_converged): `value` extrapolated
  // (Richardson, first order) to a grid without discretisation error, from the linear response
  // of the optimum to twice the cells; `value` without the grid check. `value` is the one that makes THIS model
  // reproduce the recordings (the calibrated scenario holds it); `converged` is the estimate of the
  // physical parameter, for a measured coefficient or a model on another grid. Its uncertainty is
  // `std` (the numerical part is the extrapolation's own size).
  double converged = 0.0;
  double low = 0.0, high = 0.0;
  bool at_bound = false;
  double sensitivity = 0.0;  // composite scaled sensitivity (weighted residual units)
};

// One recording and channel: fit before (the scenario as given) and after.
struct ChannelFit {
  std::string recording, channel;
  bool validation = false;   // not used in the fit
  double rms_before = 0.0, rms_after = 0.0;        // recording units (mm, l/s)
  double nrmse_before = 0.0, nrmse_after = 0.0;    // paper eq. 19, %
};

// Parameters these recordings cannot separate, with what they do determine.
struct Identifiability {
  std::vector<std::string> parameters;
  std::string reason;        // "|correlation| = 0.99", "relative std 80 %", "exact trade-off"
  std::string determined;    // the combination that is determined, in words
};

struct GridCheck {
  bool done = false;
  int factor = 2;
  double cost = 0.0, refined_cost = 0.0;   // weighted cost per sample at the optimum
  double rms_change = 0.0;   // RMS change of the predicted levels [mm]
  double residual_rms = 0.0; // RMS level residual at the optimum [mm]
  std::string verdict;
};

// Recorded, nominal and calibrated series of one recording and channel, for plots.
struct Series {
  std::string recording, channel;
  bool validation = false;
  std::vector<double> t, recorded, nominal, calibrated;
  std::vector<double> u;  // the command that drove the replay [mm], for the report's step zoom
  // The calibrated model's flow regime at each sample (RegimeCode), where the replay gives one.
  std::vector<double> regime;
};

// One gate law of CalibrateOptions::gate_laws, calibrated.
struct GateLawFit {
  scenarios::GateLaw law = scenarios::GateLaw::swamee;
  bool ok = false;
  double cost_after = 0.0;   // weighted cost per sample at its optimum
  std::string message;       // why it failed, when !ok
  bool kept = false;         // the calibration reported is this law's
};

struct Calibration {
  bool ok = true;
  std::string message;       // why it failed, when !ok
  std::vector<ParameterEstimate> parameters;
  std::vector<std::vector<double>> correlation;
  std::vector<Identifiability> identifiability;
  std::vector<ChannelFit> fits;
  GridCheck grid;
  // The optimum re-estimated on other numerics (twice the cells, the other limiter, half the
  // Courant number; discretisation.hpp); empty without the grid check.
  std::vector<DiscretisationShift> discretisation;
  std::vector<Series> series;
  double cost_before = 0.0, cost_after = 0.0;   // weighted cost per sample (fitted recordings)
  double inflation = 1.0;    // N / N_eff of the residuals at the optimum
  std::size_t samples = 0;   // residuals in the fit
  int simulations = 0, iterations = 0;   // over every grid (grid_refinements)
  // Starts run on the scenario's grid (a refined grid continues from the estimates), and why
  // further starts ran there, or why not.
  int starts = 0;
  std::string starts_note;
  // Where a parameter's scan (Parameter::scan) moved its start on the scenario's grid: to what,
  // among which values.
  std::string scan_note;
  double seconds = 0.0;
  std::string solver_report; // Ceres' one-line summary of the best run
  // The simulations' warnings, the first per recording (a failed steady state: the replay then
  // starts from time marching, and the warning names that state). Each was also passed to
  // options.replay.warning, or printed on stderr when it is unset.
  std::vector<std::string> warnings;
  // The gate laws compared (CalibrateOptions::gate_laws), empty when none were; `calibrated`
  // carries the kept one, and the "before" figures stay those of the scenario as given.
  std::vector<GateLawFit> gate_laws;
  // The grids calibrated on (CalibrateOptions::grid_refinements): the cells of every pool, the
  // scenario's first, then each refinement that lowered the cost; `calibrated` has the last.
  // The "before" figures stay those of the scenario as given.
  std::vector<std::vector<int>> grids;
  std::string grid_note;     // why the refinement stopped (empty when none was asked for)
  // A time offset between the command and the levels found after the first fit (time_offset.hpp),
  // and whether it was fitted (with the default set) or not (the parameters named); empty when
  // none was found.
  std::string time_offset_note;
  // What `calibrated` holds (CalibrateOptions::write_grid_converged): the estimates on the last
  // grid, or the grid-converged estimates on twice (or four times) its cells when they fit better
  // (written_model.hpp); then the "after" figures are those of that model. The note says which and
  // the costs compared; empty when no choice was made.
  // Where the level residual of the model written lives (residual_breakdown.hpp), without the
  // choices' shares: those are in model_forms.breakdown.
  ResidualBreakdown breakdown;
  // The model-form choices refitted (CalibrateOptions::try_model_forms); done = false when not.
  ModelForms model_forms;
  bool written_grid_converged = false;
  int written_cells_factor = 1;  // the written model's cells over the last grid's
  std::string written_note;
  scenarios::Scenario calibrated;
};

// Throws InputError for bad options, unusable recordings (check_recordings, one line naming each)
// or parameters (select_parameters); numerical failure of the nominal replay is ok = false.
Calibration calibrate(const scenarios::Scenario& scenario, const std::vector<Recording>& recordings,
                      const std::vector<Recording>& validation, const CalibrateOptions& options = {});

}  // namespace canalsim::calibration
