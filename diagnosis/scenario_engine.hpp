// The scenario engine of the diagnosis (internal to diagnosis/): the Explainer (pipeline.hpp)
// that replays the recordings through a scenario, fits each catalog effect by re-simulating (or,
// for sensor effects, by re-observing the nominal simulation) and judges it on the held-out part
// of every recording. diagnose.cpp holds the engine's core (replays, predictions, costs),
// judging.cpp its judgement of a fitted effect, scenario_fits.cpp the fit of each effect,
// joint_fit.cpp explanations of several effects and thresholds.cpp the detection thresholds.
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "calibration/observe.hpp"
#include "calibration/replay.hpp"
#include "diagnosis/catalog.hpp"
#include "diagnosis/diagnose.hpp"
#include "diagnosis/pipeline.hpp"

namespace canalsim::diagnosis::scenario_engine {

using scenarios::Scenario;
using calibration::Channels;
using Prepared = calibration::Replay;

// Evaluated hypothesis: its parameter, predictions and weighted fitted-part residual vector.
struct Point {
  double theta = 0.0;
  std::vector<Channels> prediction;
  std::vector<double> r;   // sqrt(w_c) (data - model) over the fitted parts, all channels
  double cost = 0.0;       // r·r / fitted samples
  bool on_search_grid = false;  // replayed on the search grid (Engine::Replays), not the scenario's
};

struct Costs {
  double fit = 0.0, heldout = 0.0;
  double nrmse_fit = 0.0, nrmse_heldout = 0.0;
  // Per-channel mean squared residual (raw units²) on the fitted and held-out parts.
  std::map<std::string, double> mse_fit, mse_heldout;
  // The same on the held-out part of each level channel's residual slower than the fast band
  // (calibration::slower_than_fast_band), where a calibrated model's own error is small.
  std::map<std::string, double> mse_heldout_slow;
};

// A first-order prospect — the held-out score of the fitted-part residual's least-squares step,
// linearised in the effects' parameters — stands in for a search only where it is trusted and
// far below what the search must reach: the linearised fit is optimistic (it ignores the bounds),
// so a candidate below kProspectShare of the score it needs has no chance.
inline constexpr double kProspectShare = 0.5;
// The linearised step is trusted within this many of its difference steps of every θ.
inline constexpr double kProspectSteps = 1.5;
inline constexpr double kCannotTell = std::numeric_limits<double>::infinity();  // a prospect that asks for the search

// A prediction moved to first order along signatures: each move adds per_unit × (to − from),
// channel by channel, sample by sample (over the channels of the moved prediction, which every
// `to` and `from` must cover).
struct SignatureMove {
  const std::vector<Channels>& to;
  const std::vector<Channels>& from;
  double per_unit;
};
std::vector<Channels> moved_along(std::vector<Channels> prediction, const std::vector<SignatureMove>& moves);

// The floor of a channel's reference in the channel-balanced costs [its unit]: a channel the
// nominal model already fits to within it weighs as if it missed by that much.
double cost_reference_floor(const std::string& channel);

// The scenario half of the pipeline (pipeline.hpp): replays the recordings through the scenario,
// fits each catalog effect by re-simulating (or, for sensor effects, by re-observing the nominal
// simulation) and judges it on the held-out part of every recording.
class Engine final : public Explainer {
 public:
  // How a prediction reads a quantised level: as the sensor (rounded to the lattice: piecewise
  // constant in the parameters), or as its expected reading given the model's uncertainty
  // (calibration::expected_reading: smooth, so that finite-difference Jacobians mean something).
  enum class Readings { as_sensor, expected };

  Engine(const Scenario& base, const std::vector<Recording>& recordings, const DiagnoseOptions& options)
      : base_(base), recordings_(recordings), o_(options) {}

  // Explainer:
  std::vector<RecordingResiduals> nominal_residuals() override;
  double sensor_resolution() const override { return sensors_.resolution_mm; }
  EffectResult explain(const std::string& candidate) override;
  std::vector<RecordingResiduals> residuals_with(const std::string& effect) const override;
  std::vector<RecordingSeries> series_with(const std::string& effect) const override;
  void describe(Diagnosis& d) const override;
  std::optional<JointExplanation> explain_jointly(const std::vector<ExplainedEffect>& explanation,
                                                  const std::string& candidate) override;
  void detection_thresholds(const std::vector<std::string>& candidates, const std::string& verdict,
                            Diagnosis& d) override;
  // A re-simulated effect (hydraulics, command) fitted to each recording alone by an engine of
  // that recording; nothing for an effect of the readings, whose per-recording fit would take up
  // the model's static error at each level (a constant offset is indistinguishable from it).
  std::vector<RecordingEstimate> per_recording_estimates(const std::string& effect) override;
  // The engine of the same recordings whose nominal model carries `effects` (name, parameter).
  std::unique_ptr<Engine> with_effects(const std::vector<std::pair<std::string, double>>& effects) const;
  // The level channels every recording carries, among the compared ones.
  const std::vector<std::string>& level_channels() const { return level_channels_; }

 private:
  void prepare();
  void carry_command_and_reading_effects();
  void simulate_nominal();
  void observe_nominal();  // the nominal figures from truth_
  const std::vector<Channels>& prediction_with(const std::string& effect) const;
  Costs costs(const std::vector<Channels>& prediction) const;
  // Channel-balanced cost: the mean over channels of MSE_c / MSE_c(nominal), each nominal MSE
  // floored at a sensor-noise level, so an effect that explains one channel's residual counts
  // however small that channel's share of the weighted cost (a 0.1 mm lattice error in the
  // levels next to gate-position glitches).
  double balanced(const Costs& c, bool heldout) const;
  // The same on the level channels' held-out part slower than the fast band.
  double balanced_slow(const Costs& c) const;
  Channels simulate_true(const Scenario& s, const Prepared& p);
  // The scenario that replays recording i: the base with the carried hydraulic effects.
  Scenario scenario_for(std::size_t i) const;
  // An effect at a value of its internal coordinate θ (catalog.hpp).
  struct EffectAt {
    Effect effect;
    double theta;
  };
  // What the model reads with the reading effects among `effects` (the rest are ignored).
  SensorModel sensors_with(const std::vector<EffectAt>& effects, Readings readings) const;
  std::vector<Channels> predict(const std::vector<EffectAt>& effects, Readings readings = Readings::as_sensor);
  const std::vector<Channels>& simulated(const std::vector<EffectAt>& hydraulic);
  // Where a replay runs. A search compares its points by the fitted-part residual alone, so its
  // replays may end after the fitted part (plus the lookahead a negative reading delay needs):
  // half the work at the default fit_fraction (DiagnoseOptions::search_fitted_part_only). They
  // run on the search grid (DiagnoseOptions::search_max_cells), as does a secant's probe, whose
  // whole replay gives the first-order prospects and the detection thresholds their signature.
  // The point a search returns is replayed whole on the scenario's grid (replayed_whole) before
  // anything judges it.
  enum class Replays { judged, probe, search };
  class ReplayScope {
   public:
    ReplayScope(Engine& engine, Replays replays) : engine_(engine), outer_(engine.replays_) { engine_.replays_ = replays; }
    ~ReplayScope() { engine_.replays_ = outer_; }
    ReplayScope(const ReplayScope&) = delete;
    ReplayScope& operator=(const ReplayScope&) = delete;

   private:
    Engine& engine_;
    Replays outer_;  // an enclosing scope's setting, restored on leaving
  };
  bool on_search_grid() const { return replays_ != Replays::judged && search_divisor_ > 1; }
  bool covers_heldout(const Point& p) const;
  Point replayed_whole(const std::vector<EffectAt>& effects, Point searched, Readings readings, int& sims);
  // theta = the last effect's
  Point evaluate(const std::vector<EffectAt>& effects, Readings readings = Readings::as_sensor);
  Point evaluate(const Effect& effect, double theta) { return evaluate({{effect, theta}}); }
  std::vector<double> fit_residuals(const std::vector<Channels>& prediction) const;

  // The fit of each catalog effect by its row's Search (the effect's parameter θ at its best point;
  // a re-simulated one's prediction may cover the fitted part only: replayed_whole).
  Point fit(const Effect& effect, int& sims);
  Point fit_median_offset(const Effect& effect);
  Point fit_delay_grid(const Effect& effect);
  Point fit_linear(const Effect& effect);
  Point fit_lattice(const Effect& effect);
  Point fit_gate_rate_limit(const Effect& rate_limit, int& sims);
  Point fit_by_secant(const Effect& effect, const Point& start, int& sims);
  // The held-out score, the larger of in total and slower than the fast band, of the fitted-part
  // least-squares step along the signature between the nominal point and `probe`; kCannotTell
  // beyond kProspectSteps probe steps.
  double single_prospect(const Effect& effect, const Point& probe) const;
  Point rate_limit_from_position(const Effect& rate_limit, int& sims);
  Point rate_limit_from_levels(const Effect& rate_limit, int& sims);
  EffectResult unchanged(const Effect& effect, const Costs& model) const;
  EffectResult judged_against(const Effect& effect, const Point& with, const Costs& without, double min_score,
                              bool within_calibration_counts) const;
  EffectResult judge(const Effect& effect, Point best, int sims);
  // Explanations with several effects (joint_fit.cpp).
  struct JointFit;
  JointFit fit_jointly(std::vector<EffectAt> start, const std::vector<bool>& free);
  std::vector<Channels> added_on_top(const Point& without, const Effect& added, double step);
  double joint_prospect(const std::vector<EffectAt>& held, const std::vector<bool>& free, const Point& without,
                        const Effect& added);
  std::optional<JointExplanation> spared_joint_fit(const std::vector<ExplainedEffect>& explanation,
                                                   const std::vector<EffectAt>& held, const std::vector<bool>& free,
                                                   const Point& without, const Effect& added);
  std::optional<JointExplanation> explain_on_top(const std::vector<ExplainedEffect>& explanation,
                                                 const std::string& candidate) const;
  // |∂r/∂θ|² of the fitted-part residual vector: the secant between the estimate and the nominal
  // point (0 when they coincide).
  double sensitivity(const Effect& effect, const Point& best) const;
  double parameter_std(const Effect& effect, const Point& best) const;
  // How far the calibration's residual on its baseline (DiagnoseOptions::baseline_rms_*) could
  // move θ, were it all along the effect's signature: |e| / |∂r/∂θ| (0 uncalibrated).
  double model_error_energy() const;
  double model_error_theta(const Effect& effect, const Point& best) const;
  bool beyond_calibration(const Effect& effect, double parameter) const;
  // Material: beyond the catalog's smallest change of interest or, against a calibration, beyond
  // the model-error bound; and, where `within_calibration_counts`, beyond_calibration().
  bool material(const Effect& effect, double parameter, bool within_calibration_counts) const;
  // The recorded level channels an effect reads: its own channel, or every level channel.
  std::vector<std::string> channels_of(const Effect& effect) const;
  double lattice_resolution(const std::vector<std::string>& channels) const;
  double lattice_phase(const std::string& channel, double resolution) const;
  double reading_spread(double resolution) const;
  double heldout_coherence(double r, const std::vector<std::string>& channels) const;
  // Detection thresholds (thresholds.cpp).
  struct Signature;
  Signature signature_of(const Effect& effect, const std::vector<Channels>& model, const std::vector<Channels>& base);
  DetectionThreshold threshold_of(const Effect& effect, const Signature& signature,
                                  const std::vector<ChannelFigures>& channels, double none_noise_factor) const;

  Scenario base_;                    // with the hydraulic effects an explanation carries (with_effects)
  // The command and reading effects an explanation carries (with_effects), applied in prepare().
  std::vector<std::pair<Effect, double>> carried_;
  std::vector<double> carried_inflow_m3s_;  // the reference of a carried share of the inflow
  const std::vector<Recording>& recordings_;
  const DiagnoseOptions& o_;
  std::vector<Prepared> recs_;
  SensorModel sensors_;
  double period_ = 0.13;
  std::map<std::string, double> scale_, weight_;
  std::vector<Channels> truth_;      // nominal, ideal sensors
  std::vector<Channels> nominal_;    // nominal, scenario sensors
  std::vector<double> inflow_m3s_;
  Point nominal_point_;
  Costs nominal_costs_;
  double inflation_ = 1.0;           // N / N_eff of the nominal primary residual
  std::size_t fit_samples_ = 0;
  std::map<std::string, Point> best_;
  // Each candidate as judge() found it on its own: significant, and its held-out score.
  struct JudgedAlone {
    bool significant = false;
    double score = 0.0;
  };
  std::map<std::string, JudgedAlone> judged_alone_;
  // The searches stopped at their probe (DiagnoseOptions::screen_single_fits), by candidate: the
  // prospect that stopped them. An engine that fits one recording alone for an estimate searches
  // every candidate to its best point.
  std::map<std::string, double> stopped_at_probe_;
  bool screen_searches_ = true;
  // simulated(): by effect and θ, on the search grid or not, and whether the replays end after the
  // fitted part
  using SimulationKey = std::tuple<std::vector<std::pair<std::string, double>>, bool, bool>;
  std::map<SimulationKey, std::vector<Channels>> simulations_;
  Replays replays_ = Replays::judged;  // within a ReplayScope, its setting
  // The search grid has 1/search_divisor_ of the scenario's cells (DiagnoseOptions::
  // search_max_cells); each replay on it is corrected by the nominal model's difference between
  // the two grids (per recording and channel: truth_ minus the nominal replayed on the search
  // grid; computed at the first such replay).
  int search_divisor_ = 1;
  std::vector<Channels> grid_correction_;
  void correct_for_search_grid();
  std::size_t lookahead_ = 0;        // samples a search replay runs past the fitted part
  std::vector<std::string> level_channels_;
  int simulations_run_ = 0;          // replays of all recordings simulated() ran
};


}  // namespace canalsim::diagnosis::scenario_engine
