// Diagnosis of a reduced model (LIOM, LFOM, NLIOM/NLFOM-S/F, ...) against recordings: the
// counterpart of diagnose() for `canalsim diagnose --model M`. Same steps, same result type:
//
//   1. Nominal: one parameter set (IAE_c, eq. 21) is fitted on the leading `fit_fraction` of
//      every recording; residual = recording − model on the primary channel y_dwe_mm.
//   2. Locate (locate.hpp) and test the residuals (residual_tests.hpp).
//   3. Explain: every candidate is an extension of the reduced model with its own parameter,
//      fitted on the same leading part and judged on the held-out rest:
//        gate_rate_limit           the gate follows the command at a finite speed (eq. 16)
//        sensor_quantization       the recorded levels lie on a coarser lattice (eq. 17)
//        upstream_level_variation  the head term of the nonlinear models (eq. 12–15, γ) for a
//                                  linear model: free or submerged by the recordings' regime
//        flow_regime_switch        the hybrid model that switches between the free and the
//                                  submerged submodel by conditions (8)/(10)
//        wave_resonance            a lightly damped mode of the pool (a seiche between the
//                                  gates) excited by the gate moves: a second-order band-pass
//                                  of the delayed input added to the output
//      The scenario catalog's other effects (sensor_delay, sensor_offset, gate_leakage,
//      discharge_coefficient, friction, lateral_outflow, downstream_gate) change only the delay,
//      operating point, gain or time constant of a reduced model, which the nominal fit already
//      adjusts: they are listed with that note and never named.
//      Score = relative reduction of the held-out mean squared residual; an effect is
//      significant when the score ≥ min_score, its BIC on the fitted part improves by at least
//      min_bic_gain (samples corrected for residual correlation) and its parameter is material.
//   4. Verdict: the best significant effect, else `none` (within the noise) or `unexplained`.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "diagnosis/diagnose.hpp"
#include "reduced_models/data.hpp"
#include "reduced_models/models.hpp"

namespace canalsim::diagnosis {

struct ModelDiagnoseOptions {
  reduced::ModelKind kind = reduced::ModelKind::lfom;
  double fit_fraction = 0.5;       // leading share of each recording used for fitting; (0.1, 0.9)
  double min_score = 0.15;         // held-out reduction of the squared residual; (0, 1)
  double min_bic_gain = 10.0;      // BIC improvement on the fitted part; >= 0
  double none_noise_factor = 3.0;  // "within the noise": residual RMS <= this × noise; > 0
  // Leading seconds left out of costs and tests; >= 0. None by default: the model starts from the
  // recording's own initial level and opening, so every sample counts.
  double warmup_s = 0.0;
  // Effects the nominal model already includes (eqs. 16–17); 0 = off.
  double quantum_mm = 0.0;
  double gate_speed_mm_s = 0.0;
  std::vector<std::string> candidates;  // empty = all of model_effect_names()
  reduced::DataOptions data;            // operating point, constant upstream level
  ResidualTestOptions tests;
  LocateOptions locate;
  ProgressCallback progress;
  Status validate() const;
};

// The effect names `diagnose --model` knows: the scenario catalog's and the three of reduced
// models (upstream_level_variation, flow_regime_switch, wave_resonance).
// A per-channel catalog row named without its channel stands for it on y_dwe_mm, the channel a
// reduced model predicts ("sensor_quantization" → "sensor_quantization[y_dwe_mm]").
std::string model_effect_name(const std::string& name);
std::vector<std::string> model_effect_names();

// Runs the diagnosis. Throws InputError on invalid options, unknown candidates or recordings
// the model cannot use (each named); a numerical failure is returned as ok = false.
Diagnosis diagnose_model(const std::vector<Recording>& recordings, const ModelDiagnoseOptions& options);

// The response of the damped mode ω² / (s² + 2ζωs + ω²) and of its band-pass companion
// 2ζω s / (s² + 2ζωs + ω²) to the input x sampled every h (exact zero-order-hold
// discretisation of the state-space form; exposed for tests).
struct ModeResponse {
  std::vector<double> low_pass, band_pass;
};
ModeResponse damped_mode_response(const std::vector<double>& x, double h, double frequency_hz, double damping);

}  // namespace canalsim::diagnosis
