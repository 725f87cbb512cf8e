// The scenario engine's judgement of a fitted effect (scenario_engine.hpp): its held-out score,
// BIC and channel-by-channel improvement against the model without it, its uncertainty, and
// whether it is material — beyond the catalog's smallest change of interest or, against a
// calibration, beyond the bias the calibrated model's own error could put on it, and beyond what
// the calibration leaves open.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "calibration/observe.hpp"
#include "core/format.hpp"
#include "diagnosis/calibrated.hpp"
#include "diagnosis/scenario_engine.hpp"

namespace canalsim::diagnosis::scenario_engine {
namespace {

// Whether an effect's held-out fit improves (EffectResult::heldout_improves): the primary
// channel's held-out mean squared residual falls, or another level channel's falls by 1 % while
// the primary's rises by no more than 10 % and the square of a sensor step (0.05 mm), which is
// what a refit's noise moves. The first is the rule for physics that moves the levels downstream,
// the second for the fault of a sensor elsewhere, which leaves the primary channel as it was.
void judge_by_channel(const Costs& without, const Costs& with, const std::string& primary, EffectResult& out) {
  const auto mse = [](const Costs& c, const std::string& channel) {
    const auto it = c.mse_heldout.find(channel);
    return it == c.mse_heldout.end() ? 0.0 : it->second;
  };
  constexpr double kStep = 0.05;
  const double before = mse(without, primary), after = mse(with, primary);
  if (after > 1.1 * before + kStep * kStep) out.worsened = primary;
  bool elsewhere = false;
  for (const auto& [channel, b] : without.mse_heldout) {
    if (channel != primary && calibration::is_level(channel) && mse(with, channel) < 0.99 * b) elsewhere = true;
  }
  out.heldout_improves = after < before || (elsewhere && out.worsened.empty());
}

}  // namespace

double Engine::sensitivity(const Effect& effect, const Point& best) const {
  double jj = 0.0;
  const double d_theta = best.theta - (std::isnan(nominal_point_.theta) ? effect.kind->theta_none : nominal_point_.theta);
  if (std::abs(d_theta) > 0.0) {
    for (std::size_t k = 0; k < best.r.size(); ++k) {
      const double j = (best.r[k] - nominal_point_.r[k]) / d_theta;
      jj += j * j;
    }
  }
  return jj;
}

// Uncertainty of the parameter: the residual sensitivity between the estimate and the nominal
// point (a secant Jacobian), inflated by the residual correlation, mapped from θ to the
// parameter's unit.
double Engine::parameter_std(const Effect& effect, const Point& best) const {
  const double jj = sensitivity(effect, best);
  if (!(jj > 0.0) || best.r.size() <= 1) return 0.0;
  const double sse = std::inner_product(best.r.begin(), best.r.end(), best.r.begin(), 0.0);
  const double theta_sd = std::sqrt(sse / static_cast<double>(best.r.size() - 1) / jj * inflation_);
  return theta_sd * parameter_per_theta(effect, best.theta);
}

// The baseline's residual energy |e|² over the fitted parts, channel by channel in the cost's
// weights: what the calibrated model misses on clean recordings of this length (0 uncalibrated).
double Engine::model_error_energy() const {
  double energy = 0.0;
  for (const auto& p : recs_) {
    for (const auto& [name, y] : p.data) {
      if (!calibration::is_level(name)) continue;
      const auto own = o_.baseline_rms_by_channel.find(name);
      const double rms = own != o_.baseline_rms_by_channel.end() && own->second > 0.0 ? own->second : o_.baseline_rms_mm;
      energy += weight_.at(name) * rms * rms * static_cast<double>(p.n_fit);
    }
  }
  return energy;
}

// The bound of the bias a model error e puts on a least-squares θ: |Δθ| = |e·j| / |j|² <= |e| / |j|
// (Cauchy–Schwarz).
double Engine::model_error_theta(const Effect& effect, const Point& best) const {
  const double energy = model_error_energy();
  if (energy == 0.0) return 0.0;
  const double jj = sensitivity(effect, best);
  return jj > 0.0 ? std::sqrt(energy / jj) : std::numeric_limits<double>::infinity();
}

// The catalog's smallest change of interest stands for what an uncalibrated scenario may be off
// by. Against a calibration the model's own error is measured, and a departure beyond the bias
// that error could put on the estimate (model_error_theta, at the effect's own fit) cannot be the
// model's error either (a bed 20 % rougher than calibrated, |ln 1.2| = 0.18 below the row's 0.3,
// is a change of the canal: docs/diagnosis.md, "Against a calibrated scenario").
bool Engine::material(const Effect& effect, double parameter, bool within_calibration_counts) const {
  if (within_calibration_counts && !beyond_calibration(effect, parameter)) return false;
  if (is_material(effect, parameter)) return true;
  const auto best = best_.find(effect.name());
  if (model_error_energy() == 0.0 || best == best_.end()) return false;
  return std::abs(to_theta(effect, parameter) - effect.kind->theta_none) > model_error_theta(effect, best->second);
}

// Whether the effect moves the calibrated physics by more than calibrated_z standard deviations of
// what the baseline calibration left open (diagnosis/calibrated.hpp); true for an uncalibrated
// scenario.
bool Engine::beyond_calibration(const Effect& effect, double parameter) const {
  double opening = 0.0;
  for (const auto& p : recs_) opening += p.operating_point_mm / static_cast<double>(recs_.size());
  const double open = o_.calibrated_z * calibration_uncertainty(effect, base_, o_.calibrated_std, opening);
  return open == 0.0 || departure(effect, parameter) > open;
}

// An effect's result before it is fitted: its names, and the figures of `model` (the nominal
// one, or an explanation without the effect) before and after.
EffectResult Engine::unchanged(const Effect& effect, const Costs& model) const {
  EffectResult out;
  out.name = effect.name();
  out.parameter.name = effect.kind->parameter;
  out.parameter.unit = effect.kind->unit;
  out.cost_before = out.cost_after = balanced(model, false);
  out.heldout_cost_before = out.heldout_cost_after = balanced(model, true);
  out.heldout_slow_cost_before = out.heldout_slow_cost_after = balanced_slow(model);
  out.nrmse_before = out.nrmse_after = model.nrmse_fit;
  out.heldout_nrmse_before = out.heldout_nrmse_after = model.nrmse_heldout;
  return out;
}

// Scores the model `with` the effect (at with.theta) against the model `without` it: costs before
// and after, held-out score, BIC, material and significance (pipeline.hpp's rule, with a held-out
// score of at least `min_score`). `within_calibration_counts`: the parameter must also exceed what
// the calibration leaves open (false where a jointly refitted effect spans that, calibrated.hpp).
EffectResult Engine::judged_against(const Effect& effect, const Point& with, const Costs& without, double min_score,
                                    bool within_calibration_counts) const {
  EffectResult out = unchanged(effect, without);
  const Costs after = costs(with.prediction);
  out.cost_after = balanced(after, false);
  out.heldout_cost_after = balanced(after, true);
  out.heldout_slow_cost_after = balanced_slow(after);
  out.nrmse_after = after.nrmse_fit;
  out.heldout_nrmse_after = after.nrmse_heldout;
  out.score = out.heldout_cost_before > 0.0 ? (out.heldout_cost_before - out.heldout_cost_after) / out.heldout_cost_before : 0.0;
  out.slow_score = out.heldout_slow_cost_before > 0.0
                       ? (out.heldout_slow_cost_before - out.heldout_slow_cost_after) / out.heldout_slow_cost_before
                       : 0.0;
  const double n_eff = static_cast<double>(fit_samples_) / inflation_;
  out.delta_bic = bic_change(n_eff, out.cost_before, out.cost_after);
  out.parameter.value = to_parameter(effect, with.theta);
  out.material = material(effect, out.parameter.value, within_calibration_counts);
  // "Show the fit improve": the held-out fit must improve on some channel and get materially worse
  // on none, so that a pooled cost cannot name an effect that fits the upstream channels while the
  // levels downstream get worse (seen on calibrated realistic truths), nor miss one that fits a
  // faulty upstream sensor and leaves the rest as it was.
  judge_by_channel(without, after, o_.primary, out);
  const SignificanceRule rule{min_score, o_.min_bic_gain, true};
  out.significant = is_significant(out, rule);
  out.set_aside = set_aside_reason(out, rule);
  return out;
}

// An effect at its fitted point, judged against the nominal model, with its uncertainty.
EffectResult Engine::judge(const Effect& effect, Point fitted, int sims) {
  const Point& best = best_[effect.name()] = std::move(fitted);  // material() reads the effect's own fit
  EffectResult out = judged_against(effect, best, nominal_costs_, o_.min_score, true);
  out.simulations = sims;
  out.parameter.std = parameter_std(effect, best);
  if (effect.kind->search == Search::lattice) {
    // A quantised reading is best predicted in the mean-square sense by the unquantised level, so
    // the squared-error cost cannot reward this effect. Its evidence is the lattice: a step at
    // least twice the modelled resolution, and the lattice coherence of the held-out levels at
    // the step fitted on the first part as the score.
    const double value = std::max(out.parameter.value, sensors_.resolution_mm);
    out.parameter.value = value;
    out.material = value >= std::max(effect.kind->material, 2.0 * sensors_.resolution_mm);
    out.score = out.material ? heldout_coherence(value, channels_of(effect)) : 0.0;
    out.slow_score = 0.0;
    out.significant = out.material && out.score >= 0.9;
    out.set_aside = out.significant ? ""
                    : !out.material ? "the recorded lattice is the modelled resolution"
                                    : "lattice coherence " + format_g(out.score, 2) + " < 0.9";
  }
  if (const auto stopped = stopped_at_probe_.find(out.name); stopped != stopped_at_probe_.end() && !out.significant) {
    out.set_aside += std::string(out.set_aside.empty() ? "" : "; ") + "its first-order prospect from the probe, a held-out score of " +
                     format_g(stopped->second, 2) + ", is below " + format_g(kProspectShare * o_.min_score, 2) +
                     ": searched no further";
  }
  judged_alone_[out.name] = {out.significant, out.score};
  return out;
}

}  // namespace canalsim::diagnosis::scenario_engine
