// The calibrated model's form put to the test: each model-form choice the scenario and the
// calibration leave open is added in turn and the calibration refitted from the estimates, so the
// part of the residual it removes is measured, not guessed.
//
//   1. The choices that apply: a parameter of the model's form not fitted yet — a head-gate
//      discharge coefficient that varies with the opening (a power law, the simplest gate
//      rating; with the submerged multiplier's blend it varies with opening and submergence), the
//      head gate's submerged law regularised near zero head, a time offset between the command
//      and the levels, the level beyond the downstream gate, and — where the scenario's reservoir
//      feeds the head gate — a pump whose flow lags its drive and the pump controller's gains;
//      and one swap of structure, a free
//      weir in place of a fixed downstream gate (its crest set where it passes what the gate
//      passes at the mean recorded end level, then fitted; the gate's parameters dropped). (The gate law itself is compared by
//      CalibrateOptions::gate_laws, each law calibrated from the scenario's values: the laws'
//      coefficients mean different things, so one law's estimates are no start for the other.
//      A finite actuator speed, paper eq. 16, is not among them: an ideal gate lies outside its
//      bounds, so no refit starts where it changes nothing, and the lag of a slow gate is first
//      taken by the time offset the calibration fits.)
//   2. The calibration as it stands refitted on the same terms (the grid it started on, one
//      start, no grid check), then each choice from the same estimates, its parameter starting
//      where it changes nothing (the weir: where it holds the gate's operating point; the pump's
//      lag, whose cost is not monotone from 0, at the best value of a scan).
//   3. Each choice scored by the Bayesian information criterion on the effective samples,
//        ΔBIC = N_eff ln(cost / cost₀) + Δk ln N_eff,
//      N_eff the fitted residuals over their autocorrelation inflation (calibrate.hpp: the
//      residuals of a canal are far from independent, and N itself would let any added parameter
//      pay), and, when there are validation recordings, by their RMS level residual. A choice
//      pays when its ΔBIC is below −10 ("very strong" evidence on Kass & Raftery's 1995 scale)
//      and it does not fit the validation recordings worse.
//   4. Each choice that pays is refitted on twice the cells, against the calibration refitted
//      there, and keeps "pays" only if it pays there too and removes at least 15 % of the cost
//      (the share the calibration's time-offset scan asks of a delay, time_offset.hpp): one that
//      paid by standing in for the discretisation (a time offset of a tenth of a sample for the
//      scheme's phase error) does not.
//   5. Each other choice that still pays is refitted on top of the one that pays most, and keeps
//      "pays" only if it pays there and removes 15 % of what is left: one that stood in for it
//      (a regularised gate law, or a rating, for a tail level) does not.
#pragma once

#include <string>
#include <vector>

#include "calibration/residual_breakdown.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

struct Calibration;
struct CalibrateOptions;

// A parameter the choice fitted, at its estimate.
struct FormEstimate {
  std::string name, unit;
  double value = 0.0, std = 0.0;
};

// One model-form choice, refitted.
struct ModelFormTrial {
  // cd_opening_exponent, zero_head_mm, border_floor_ratio, sensor_delay_s, weir_crest_mm,
  // pump_lag_s, pump_controller, tail_level_mm
  std::string name;
  std::string description;  // what the choice adds to the model, in words
  int added_parameters = 0;  // negative for a swap that drops more than it adds
  bool ok = false;
  std::string message;      // why the refit failed, when !ok
  double cost = 0.0;        // weighted cost per sample on the fitted recordings
  double removed = 0.0;     // 1 − cost / cost₀: the share of the refitted cost it removes
  double bic_change = 0.0;  // negative: the information criterion prefers the choice
  // RMS level residual over the validation recordings' level channels [mm]; NaN without them.
  double validation_rms_mm = 0.0;
  bool pays = false;
  // For a choice that paid on the scenario's grid: what it does on twice the cells, and on top of
  // the choice that pays most (`pays` is false when it does not pay there).
  std::string note;
  std::vector<FormEstimate> estimates;  // the parameters the choice added
};

struct ModelForms {
  bool done = false;
  std::string message;                  // why the comparison did not run, when !done
  double cost = 0.0;                    // the calibration as it stands, refitted on the same terms
  double validation_rms_mm = 0.0;       // its validation RMS [mm]; NaN without validation recordings
  double effective_samples = 0.0;       // N_eff of the information criterion
  std::vector<ModelFormTrial> trials;   // by ΔBIC, the most preferred first
  double seconds = 0.0;
  int simulations = 0;
  std::string verdict;                  // one line: the choice that pays most, or that none does
  // Where the reference's level residual lives and the share each choice's refit removes there.
  ResidualBreakdown breakdown;
};

// The comparison for the calibration `c` of `scenario` to `recordings` (with `validation` held
// out) made with `options`; c must be ok. Each refit is a calibrate() call on the scenario's own
// grid: about the time of a calibration from its estimates per choice.
ModelForms compare_model_forms(const scenarios::Scenario& scenario, const Calibration& c, const std::vector<Recording>& recordings,
                               const std::vector<Recording>& validation, const CalibrateOptions& options);

}  // namespace canalsim::calibration
