// One diagnosis pipeline for every kind of model (docs/diagnosis.md), written once:
//
//   1. nominal residuals → locate the mismatch (locate.hpp) and test it (residual_tests.hpp);
//      the noise figures of the recordings;
//   2. explain: every candidate effect fitted and judged on held-out data (by the Explainer);
//   3. rank: significant first, then effects that could be evaluated, then by score;
//   4. verdict: the best significant effect, else `none` (within the noise) or `unexplained`;
//   5. explanation with several effects: each remaining candidate is fitted jointly
//      with the effects found so far (all their parameters free) and the best one added while its
//      held-out gain over the explanation without it stays significant. A significant runner-up
//      such that neither it adds to the verdict nor the verdict to it is reported with the
//      verdict as an ambiguous pair (the recordings cannot tell them apart), with the experiment
//      that would. A verdict that explains alone (nothing added to it) then has its form checked
//      across the recordings: its parameter, fitted to each recording alone, must be one
//      constant of the canal (a catalog row's parameter is). Estimates that differ between
//      operating points far beyond what the model's error moves them mean physics the catalog
//      does not have: the verdict becomes `unexplained`, located, with the effect as the
//      catalog's nearest row;
//   6. the corrected prediction of the verdict → locate and test again;
//   7. what the recordings cannot show: each candidate's detection threshold, from the residual
//      the model with the verdict leaves and the candidate's signature (its prediction's change
//      per unit of its parameter), under the significance rule (Explainer::detection_thresholds).
//
// An Explainer is the model-specific part: the scenario engine (diagnose.hpp, re-simulating the
// canal) and the reduced-model engine (model_diagnosis.hpp, refitting a reduced model) implement
// it. The significance rule and the BIC are written here once and used by both.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/progress.hpp"
#include "diagnosis/discrepancy.hpp"
#include "diagnosis/locate.hpp"
#include "diagnosis/residual_tests.hpp"

namespace canalsim::diagnosis {

struct ParameterEstimate {
  std::string name;
  std::string unit;
  double value = 0.0;
  double std = 0.0;   // one standard deviation; 0 when the cost was flat or at a bound
};

struct EffectResult {
  std::string name;
  double score = 0.0;            // relative held-out cost reduction (1 = perfect, < 0 = worse)
  bool significant = false;
  bool material = false;
  ParameterEstimate parameter;
  double nrmse_before = 0.0, nrmse_after = 0.0;                  // primary, fitted part, mean over recordings
  double heldout_nrmse_before = 0.0, heldout_nrmse_after = 0.0;  // primary, held-out part
  double cost_before = 0.0, cost_after = 0.0;                    // channel-balanced, fitted part
  double heldout_cost_before = 0.0, heldout_cost_after = 0.0;
  // The same on the level channels' held-out part slower than the fast band
  // (calibration::slower_than_fast_band), and its relative reduction; 0 where the engine does
  // not measure it.
  double heldout_slow_cost_before = 0.0, heldout_slow_cost_after = 0.0;
  double slow_score = 0.0;
  double delta_bic = 0.0;        // BIC(after) − BIC(before) on the fitted part
  // The held-out fit improves on some compared channel and gets materially worse on none (the
  // engine's judgement; for one channel: its held-out Nrmse rises).
  bool heldout_improves = false;
  std::string worsened;          // a channel whose held-out fit the effect makes worse, if any
  std::string set_aside;         // why a fitted effect is not significant (set_aside_reason)
  int simulations = 0;           // re-simulations spent on the fit
  std::string note;              // why it was skipped, if it was
};

// One effect of an explanation with several effects.
struct ExplainedEffect {
  std::string name;
  ParameterEstimate parameter;   // refitted with the explanation's other effects in place
  double score = 0.0;            // held-out cost reduction when added to the effects before it
  double share = 0.0;            // share of the nominal held-out cost it removes
};

// Two effects the recordings cannot tell apart: each explains the residual about as well as the
// other, and neither adds to the other.
struct AmbiguousPair {
  std::string first, second;     // first = the verdict
  ParameterEstimate first_parameter, second_parameter;
  double first_score = 0.0, second_score = 0.0;
  std::string separating_experiment;
};

// A candidate fitted jointly with an explanation (Explainer::explain_jointly).
struct JointExplanation {
  EffectResult added;                        // judged against the explanation without it
  std::vector<ParameterEstimate> refitted;   // the explanation's effects, in its order, refitted with it
  // For an explanation of one effect: that effect is significant on top of the candidate alone
  // (when neither is on top of the other, the two are an ambiguous pair).
  bool explanation_adds = false;
};

// What the nominal model misses on one level channel, against what that channel's noise and the
// calibration's baseline make ordinary.
struct ChannelFigures {
  std::string name;
  double noise = 0.0;       // estimated from the recorded channel itself [mm]
  double rms = 0.0;         // nominal residual RMS [mm]
  double tolerated = 0.0;   // what the calibration leaves on its baseline, times the factor [mm]; 0 = none
  // The residual's part slower than the fast band (calibration::slower_than_fast_band) [mm], and
  // what the calibration leaves of that part on its baseline, times the factor (0 = not known),
  // but at least none_noise_factor × what the noise leaves of it, noise / sqrt(samples averaged).
  double slow_rms = 0.0, slow_tolerated = 0.0;
  // rms ≤ none_noise_factor × noise, or rms ≤ tolerated with slow_rms ≤ slow_tolerated (when
  // known): within the noise, or within the model's own error in total and in the slower part,
  // where a bore's smearing does not reach
  bool ordinary = true;
};

// What the recordings cannot show: the smallest value of an effect's parameter, on either side of
// "no effect", that these recordings would reveal against the model under the pipeline's own
// significance rule (step 7 of the pipeline). The effect is revealed when its parameter is
// at most `below` or at least `above` (NaN: no such side within the catalog's range).
struct DetectionThreshold {
  std::string effect;
  std::string parameter, unit;
  double below = 0.0, above = 0.0;
  // Whether a parameter value would be revealed.
  bool reveals(double value) const;
};

// Per-recording series for plots (primary channel, mm).
struct RecordingSeries {
  std::string name;
  std::vector<double> t, u, recorded, nominal, corrected;
  std::size_t fit_samples = 0;
};

// Where an unexplained residual lives, and what a data-driven correction makes of it.
struct UnexplainedResidual {
  std::string channel;           // the level channel furthest beyond its noise and tolerance
  Mismatch where;                // that channel's residual located (locate.hpp)
  // A low-order filter from the command to each level channel's residual (discrepancy.hpp): a
  // description of the missing physics, not physics.
  std::vector<DiscrepancyModel> discrepancy;
  std::string summary;           // in words: channel, regime, operating point, windows, band, form
};

// The verdict's parameter fitted to each recording alone (step 5).
struct RecordingEstimate {
  std::string recording;
  ParameterEstimate parameter;
  // The estimate's departure from "no effect" in the effect's internal coordinate (catalog.hpp),
  // and its standard deviation there: comparable between recordings and effects.
  double departure = 0.0, departure_std = 0.0;
  // How far the model's own error could move the departure: the residual a calibration leaves on
  // its baseline, were it all along the effect's signature in this recording (0 uncalibrated).
  double model_error = 0.0;
  // Whether the estimate took part in the comparison (check_form): the model's error could move
  // it by less than the departures' mean size.
  bool compared = true;
};

struct FormCheck {
  std::string effect;
  std::vector<RecordingEstimate> estimates;
  // (largest − smallest departure) / |mean departure| over the compared estimates; NaN when that
  // mean is 0 or fewer than two are compared (the form then holds: nothing contradicts it).
  double relative_spread = 0.0;
  bool holds = true;
};

struct Diagnosis {
  bool ok = true;
  std::string message;           // numerical failure (a simulation that did not run), when !ok
  std::string verdict;           // none | unexplained | an effect name
  std::string reason;            // one sentence on how the verdict was reached
  std::vector<EffectResult> effects;   // ranked, best first
  std::vector<ExplainedEffect> explanation;  // the verdict first, then each effect added; empty without a verdict
  std::vector<AmbiguousPair> ambiguous;
  // The form check of a verdict that explains alone (step 5); nullopt when the engine cannot
  // fit it per recording, or there is one recording.
  std::optional<FormCheck> form;
  Mismatch mismatch;             // of the nominal model
  Mismatch mismatch_after;       // with the winner (equals mismatch when there is none)
  std::vector<ResidualTests> tests_before, tests_after;  // per recording, primary channel
  double noise = 0.0;            // estimated measurement noise of the primary channel [mm]
  double noise_limit_nrmse = 0.0;  // Nrmse a perfect model would reach given that noise
  double nominal_rms = 0.0;      // primary residual RMS of the nominal model [mm]
  std::vector<ChannelFigures> channels;  // every level channel, the primary first
  std::vector<DetectionThreshold> thresholds;  // per candidate the engine can judge so
  // With the verdict `unexplained`; with an effect, what the model with it still leaves beyond
  // the noise and the calibration's tolerance on some level channel (a partial explanation).
  std::optional<UnexplainedResidual> unexplained;
  std::string lowering_experiment;   // the experiment that would lower the largest thresholds
  std::vector<RecordingSeries> series;
  std::map<std::string, double> channel_scale;  // s_c of the cost weights
  // The scenario engine's grids, in cells over all pools: the model's, and the one its searches
  // replayed on (DiagnoseOptions::search_max_cells); 0 for the reduced-model engine.
  int model_cells = 0, search_cells = 0;
  double seconds = 0.0;
};

// The model-specific half of a diagnosis.
class Explainer {
 public:
  virtual ~Explainer() = default;
  // Runs the nominal model (simulation or fit) and returns its residuals, one set per recording.
  virtual std::vector<RecordingResiduals> nominal_residuals() = 0;
  // Resolution of the level sensors in the nominal model [mm] (floor of the noise estimate).
  virtual double sensor_resolution() const = 0;
  // Fits one candidate effect and judges it (score, BIC, significance).
  virtual EffectResult explain(const std::string& candidate) = 0;
  // Residuals and plotted series with an explained effect's corrected prediction ("" = nominal).
  virtual std::vector<RecordingResiduals> residuals_with(const std::string& effect) const = 0;
  virtual std::vector<RecordingSeries> series_with(const std::string& effect) const = 0;
  // Extra figures of the result (the scenario engine's channel scales).
  virtual void describe(Diagnosis&) const {}
  // `candidate` added to an explanation of several effects (step 5): fitted jointly with the
  // explanation's effects — every parameter free, since effects that shift the levels alike
  // trade off, and one fitted alone absorbs part of the other — and judged against the model
  // carrying the explanation alone. nullopt when the engine cannot explain with several effects.
  virtual std::optional<JointExplanation> explain_jointly(const std::vector<ExplainedEffect>& /*explanation*/,
                                                          const std::string& /*candidate*/) {
    return std::nullopt;
  }
  // Step 5's form check: the effect fitted to each recording alone, or nothing when the engine
  // does not check this effect's form.
  virtual std::vector<RecordingEstimate> per_recording_estimates(const std::string& /*effect*/) { return {}; }
  // Step 7: the detection threshold of each candidate against the model with `verdict` ("" =
  // nominal), and the experiment that would lower the largest (d.thresholds,
  // d.lowering_experiment). Nothing when the engine cannot compute them.
  virtual void detection_thresholds(const std::vector<std::string>& /*candidates*/, const std::string& /*verdict*/,
                                    Diagnosis& /*d*/) {}
};

// The significance rule of every engine: a material parameter, a held-out cost reduction of at
// least min_score and a BIC gain of at least min_bic_gain; optionally the held-out fit must
// improve on a channel and worsen on none too ("show the fit improve": a pooled cost can fall
// through one channel or recording while another gets worse).
struct SignificanceRule {
  double min_score = 0.15;
  double min_bic_gain = 10.0;
  bool heldout_fit_must_improve = false;
};

struct PipelineSettings {
  double none_noise_factor = 3.0;  // "within the noise": a channel's RMS <= this × its noise
  // The engine's significance rule, applied by step 4 to the held-out cost slower than the fast
  // band when only that part of a channel is beyond what the calibration tolerates.
  SignificanceRule significance;
  // A primary RMS up to this is ordinary too [mm] (what a calibration leaves on its baseline).
  double tolerated_rms = 0.0;
  // The same for other level channels, by name; a channel without one takes tolerated_rms.
  std::map<std::string, double> tolerated_by_channel;
  // The same for the part of each channel's residual slower than the fast band, by name; a channel
  // without one is judged in total only.
  std::map<std::string, double> tolerated_slow_by_channel;
  ResidualTestOptions tests;
  LocateOptions locate;
  ProgressCallback progress;       // share of the candidates explained, and the candidate
  int max_effects = 3;             // effects in one explanation; 1 = the verdict alone
  // A significant runner-up whose score reaches this share of the verdict's is ambiguous with it
  // when neither adds significantly on top of the other.
  double ambiguity_share = 0.5;
  // Step 5: the verdict's form does not hold when its per-recording estimates spread by more than
  // this share of their mean departure from "no effect", by more than form_z of their standard
  // deviations, and by more than form_model_error of what the model's error could move the two
  // extremes apart (RecordingEstimate::model_error, a bound that puts the whole error along the
  // effect's signature). On realistic blind-test truths constant outflows of 3.7 and 12 % of the
  // inflow spread by 0.03 and 0.07 of that bound, seepages growing with the depth by 0.93 and 1.06.
  // Only the estimates the model's error could move by less than form_compared times the mean
  // size of the departures are compared: where it could move one further than the effect itself, the
  // recording says nothing of the form (a leak at an opening where the gate's law is least
  // alike between the model and the canal), and at least two must remain.
  double form_spread = 0.5;
  double form_z = 4.0;
  double form_model_error = 0.5;
  double form_compared = 1.0;
};

// Runs the pipeline over `candidates` (names the explainer knows). An InputError propagates; any
// other failure (a simulation that did not run) is returned as ok = false with its message.
Diagnosis run_pipeline(Explainer& explainer, const std::vector<std::string>& candidates,
                       const PipelineSettings& settings);

// BIC(after) − BIC(before) of an effect on the fitted part: n_eff log(cost_after / cost_before)
// + k log n_eff, with n_eff the number of samples corrected for residual correlation and k the
// parameters the effect adds (Schwarz 1978).
double bic_change(double n_eff, double cost_before, double cost_after, int extra_parameters = 1);

// Whether `effect` passes the rule (its score, or with `slower_part` its slow_score, against
// min_score).
bool is_significant(const EffectResult& effect, const SignificanceRule& rule, bool slower_part = false);
// Why `effect` fails the rule, every failed condition in words ("not material: ..."); empty when
// it passes. The engines store it in EffectResult::set_aside, so that a better-scoring candidate
// the verdict passed over says why.
std::string set_aside_reason(const EffectResult& effect, const SignificanceRule& rule);

// Noise of the primary channel estimated from the recordings themselves, the nominal residual RMS
// and the Nrmse a perfect model would reach given that noise; the same figures for every level
// channel (d.channels) with what `settings` tolerates on it (fields of `d`).
void set_noise_figures(const std::vector<RecordingResiduals>& sets, double resolution, const PipelineSettings& settings,
                       Diagnosis& d);

// The rule behind ChannelFigures::ordinary for a residual of `rms` in total and `slow_rms` in its
// part slower than the fast band, against `f`'s noise and tolerances; and whether such a residual
// is within the noise or the calibration's tolerance in total (beyond, if at all, only in its
// slower part).
bool is_ordinary(const ChannelFigures& f, double rms, double slow_rms, double none_noise_factor);
bool ordinary_in_total(const ChannelFigures& f, double rms, double none_noise_factor);

// Step 5's rule on per-recording estimates (nullopt for fewer than two).
std::optional<FormCheck> check_form(const std::string& effect, std::vector<RecordingEstimate> estimates,
                                    const PipelineSettings& settings);

// Verdict and reason from the ranked effects and the nominal residual figures: the first effect
// when it is significant (returns true); else `none` when every level channel is ordinary
// (d.channels: within none_noise_factor × its noise, or what the calibration tolerates; the
// primary also when it passes the residual tests); else `unexplained`, naming the channel.
bool set_verdict(Diagnosis& d, double none_noise_factor);

}  // namespace canalsim::diagnosis
