// What the recordings cannot show (pipeline.hpp step 7) in the scenario engine: for each candidate,
// the smallest departure from "no effect" that these recordings would reveal.
//
// Let r0 be the residual the model (with the verdict, if any) leaves, and m the candidate's
// signature: the change of the model's prediction per unit of θ, by one evaluation at the row's
// probe step (a re-simulation for the canal's physics and the command, a re-observation for an
// instrument). Recordings with the effect at δ would leave r0 + δ m against the model; fitting the
// effect by least squares on the fitted parts (the engine's weights) finds δ̂ = δ + Σw r0·m / Σw m²
// and leaves r0 − (Σw r0·m / Σw m²) m, whatever δ. Each term is a sum over channels of the
// quadratics Σ r0², Σ r0·m, Σ m², so the pipeline's own rule — held-out score on the
// channel-balanced cost, BIC gain with the correlated-sample count, materiality (the catalog's
// floor or the model-error bound) beyond the calibration's tolerance, a held-out fit that
// improves — is evaluated at any δ in closed form, and the threshold is the smallest δ on each
// side that passes it. Step 4's second route is evaluated the same way on the level channels'
// part slower than the fast band (a linear filter: the slower part of r0 + δ m is that of r0 plus
// δ times that of m): a residual beyond the calibration's tolerance only there, a candidate that
// passes the rule on that part's held-out cost and leaves every level channel ordinary. Linear in θ: a first-order picture, which the
// tests hold to "twice the threshold is named, half is not".
#include <algorithm>
#include <cmath>
#include <limits>

#include "calibration/residual_breakdown.hpp"
#include "core/format.hpp"
#include "diagnosis/calibrated.hpp"
#include "diagnosis/scenario_engine.hpp"

namespace canalsim::diagnosis::scenario_engine {

// The quadratic sums of one channel over every recording, on the fitted and the held-out parts.
struct ChannelSums {
  double rr = 0.0, rm = 0.0, mm = 0.0;  // Σ r0², Σ r0·m, Σ m²
  double n = 0.0;
  // Mean square of r0 + x m.
  double mse(double x) const { return n > 0.0 ? (rr + 2.0 * x * rm + x * x * mm) / n : 0.0; }
};

struct Engine::Signature {
  bool ok = false;
  double step = 0.0;                          // the probe step in θ
  std::map<std::string, ChannelSums> fit, heldout;
  // Level channels' parts slower than the fast band: of the whole records (the channels'
  // figures) and of the held-out parts (the score), each filtered as the engine filters it.
  std::map<std::string, ChannelSums> slow_whole, slow_heldout;
  std::vector<double> energy;                 // Σ w m² per recording (where the effect shows most)
};

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// mean_c MSE_c(x) / reference_c: the engine's channel-balanced cost of r0 + x m.
double balanced_cost(const std::map<std::string, ChannelSums>& sums, double x, const std::map<std::string, double>& reference) {
  double sum = 0.0;
  int count = 0;
  for (const auto& [c, s] : sums) {
    if (s.n == 0.0) continue;
    sum += s.mse(x) / reference.at(c);
    ++count;
  }
  return count ? sum / count : 0.0;
}

// The balanced cost's references for recordings that leave r0 + x m against the nominal model:
// their mean squares, floored as the engine floors them.
std::map<std::string, double> references_at(const std::map<std::string, ChannelSums>& sums, double x) {
  std::map<std::string, double> out;
  for (const auto& [c, s] : sums) out[c] = std::max(s.mse(x), cost_reference_floor(c) * cost_reference_floor(c));
  return out;
}

void add(ChannelSums& s, double r0, double m) {
  s.rr += r0 * r0;
  s.rm += r0 * m;
  s.mm += m * m;
  s.n += 1.0;
}

// The sums of the parts of r0 and m slower than the fast band.
void add_slower_parts(const std::vector<double>& r0, const std::vector<double>& m, double period_s, ChannelSums& s) {
  const std::vector<double> slow_r0 = calibration::slower_than_fast_band(r0, period_s);
  const std::vector<double> slow_m = calibration::slower_than_fast_band(m, period_s);
  for (std::size_t n = 0; n < slow_r0.size(); ++n) add(s, slow_r0[n], slow_m[n]);
}

// A channel's figures for recordings that leave r0 + x m against the model: ordinary as
// set_noise_figures judges it, and beyond only in its part slower than the fast band.
struct ChannelState {
  bool ordinary = true, only_slow_beyond = false;
};
ChannelState state_of(const ChannelFigures& f, double none_noise_factor, const ChannelSums& fit, const ChannelSums& heldout,
                      const ChannelSums& slow, double x) {
  const double n = fit.n + heldout.n;
  const double rms = n > 0.0 ? std::sqrt((fit.mse(x) * fit.n + heldout.mse(x) * heldout.n) / n) : 0.0;
  ChannelState s;
  s.ordinary = is_ordinary(f, rms, std::sqrt(slow.mse(x)), none_noise_factor);
  s.only_slow_beyond = !s.ordinary && ordinary_in_total(f, rms, none_noise_factor);
  return s;
}

}  // namespace

Engine::Signature Engine::signature_of(const Effect& effect, const std::vector<Channels>& model,
                                       const std::vector<Channels>& base) {
  Signature sig;
  const EffectKind& k = *effect.kind;
  sig.step = k.theta_probe;
  // The probe of the effect's secant search (on the search grid), when it had one.
  const ReplayScope probe(*this, Replays::probe);
  const std::vector<Channels> probed = predict({{effect, k.theta_none + sig.step}}, Readings::expected);
  sig.energy.assign(recs_.size(), 0.0);
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    const Prepared& rec = recs_[i];
    for (const auto& [c, y] : rec.data) {
      const auto mo = model[i].find(c), b = base[i].find(c), p = probed[i].find(c);
      if (mo == model[i].end() || b == base[i].end() || p == probed[i].end()) continue;
      const double w = weight_.at(c);
      std::vector<double> r0(rec.n), m(rec.n);
      for (std::size_t n = 0; n < rec.n; ++n) {
        r0[n] = y[n] - mo->second[n];
        m[n] = -(p->second[n] - b->second[n]) / sig.step;  // r = data − model: the model rises by −m
        add(n < rec.n_fit ? sig.fit[c] : sig.heldout[c], r0[n], m[n]);
        sig.energy[i] += w * m[n] * m[n];
      }
      if (!calibration::is_level(c)) continue;
      add_slower_parts(r0, m, period_, sig.slow_whole[c]);
      const auto split = static_cast<std::ptrdiff_t>(rec.n_fit);
      add_slower_parts({r0.begin() + split, r0.end()}, {m.begin() + split, m.end()}, period_, sig.slow_heldout[c]);
    }
  }
  double wmm = 0.0;
  for (const auto& [c, s] : sig.fit) wmm += weight_.at(c) * s.mm;
  sig.ok = wmm > 0.0;
  return sig;
}

// The threshold on each side: the smallest δ on a geometric grid from a tenth of the material
// departure to the catalog's range at which recordings with the effect would pass the rule.
DetectionThreshold Engine::threshold_of(const Effect& effect, const Signature& sig, const std::vector<ChannelFigures>& channels,
                                        double none_noise_factor) const {
  const EffectKind& k = *effect.kind;
  DetectionThreshold t{effect.name(), k.parameter, k.unit, kNaN, kNaN};
  if (!sig.ok) return t;
  double wrm = 0.0, wmm = 0.0;
  for (const auto& [c, s] : sig.fit) {
    wrm += weight_.at(c) * s.rm;
    wmm += weight_.at(c) * s.mm;
  }
  // r0 + δ m is what the model leaves of such recordings; the fit takes δ̂ m off: r0 − b m.
  const double b = wrm / wmm;
  const double n_eff = static_cast<double>(fit_samples_) / inflation_;
  double opening = 0.0;
  for (const auto& p : recs_) opening += p.operating_point_mm / static_cast<double>(recs_.size());
  const double open = o_.calibrated_z * calibration_uncertainty(effect, base_, o_.calibrated_std, opening);
  // Engine::material's bound on what the calibrated model's own error could put on θ (none uncalibrated).
  const double energy = model_error_energy();
  const double model_error = energy > 0.0 ? std::sqrt(energy / wmm) : kNaN;
  // Step 4's second route: some level channel beyond only in its slower part, none beyond in
  // total; the fit leaves every level channel ordinary and reduces that part's held-out cost by
  // min_score.
  const auto passes_slower_part = [&](double delta) {
    bool beyond = false, after_ordinary = true;
    for (const ChannelFigures& f : channels) {
      const auto fit = sig.fit.find(f.name), held = sig.heldout.find(f.name), slow = sig.slow_whole.find(f.name);
      if (fit == sig.fit.end() || held == sig.heldout.end() || slow == sig.slow_whole.end()) continue;
      const ChannelState before = state_of(f, none_noise_factor, fit->second, held->second, slow->second, delta);
      if (!before.ordinary && !before.only_slow_beyond) return false;
      beyond = beyond || before.only_slow_beyond;
      after_ordinary = after_ordinary && state_of(f, none_noise_factor, fit->second, held->second, slow->second, -b).ordinary;
    }
    if (!beyond || !after_ordinary) return false;
    const auto reference = references_at(sig.slow_heldout, delta);
    const double before = balanced_cost(sig.slow_heldout, delta, reference), after = balanced_cost(sig.slow_heldout, -b, reference);
    return before > 0.0 && (before - after) / before >= o_.min_score;
  };
  const auto passes = [&](double delta) {
    // The balanced costs take the nominal model's residual of those recordings as reference.
    const auto ref_fit = references_at(sig.fit, delta), ref_held = references_at(sig.heldout, delta);
    const double held_before = balanced_cost(sig.heldout, delta, ref_held), held_after = balanced_cost(sig.heldout, -b, ref_held);
    const double score = held_before > 0.0 ? (held_before - held_after) / held_before : 0.0;
    const double bic = bic_change(n_eff, balanced_cost(sig.fit, delta, ref_fit), balanced_cost(sig.fit, -b, ref_fit));
    const double estimate = to_parameter(effect, k.theta_none + delta - b);
    const bool material = (open == 0.0 || departure(effect, estimate) > open) &&
                          (is_material(effect, estimate) || std::abs(delta - b) > model_error);
    // The held-out fit improves: on the primary channel, or on another level channel with the
    // primary no worse (judge_by_channel).
    const auto held = sig.heldout.find(o_.primary);
    const bool primary_better = held != sig.heldout.end() && held->second.mse(-b) < held->second.mse(delta);
    bool elsewhere = false;
    for (const auto& [c, s] : sig.heldout) elsewhere = elsewhere || (c != o_.primary && calibration::is_level(c) && s.mse(-b) < 0.99 * s.mse(delta));
    if (!material || -bic < o_.min_bic_gain || !(primary_better || elsewhere)) return false;
    return score >= o_.min_score || passes_slower_part(delta);
  };
  const double first = 0.1 * k.material, range = std::max(k.theta_high - k.theta_none, k.theta_none - k.theta_low);
  for (const double side : {-1.0, 1.0}) {
    const double room = side > 0.0 ? k.theta_high - k.theta_none : k.theta_none - k.theta_low;
    if (room <= 0.0) continue;
    for (double delta = first; delta <= std::min(room, range); delta *= 1.08) {
      if (!passes(side * delta)) continue;
      (side > 0.0 ? t.above : t.below) = to_parameter(effect, k.theta_none + side * delta);
      break;
    }
  }
  // In the inverse coordinate a larger θ is a slower gate: revealed at or below that speed.
  if (k.coordinate == Coordinate::inverse) std::swap(t.below, t.above);
  return t;
}

void Engine::detection_thresholds(const std::vector<std::string>& candidates, const std::string& verdict, Diagnosis& d) {
  const std::vector<Channels>& model = prediction_with(verdict);
  const std::vector<Channels> base = predict({}, Readings::expected);
  double worst_ratio = 0.0;
  std::vector<double> worst_energy;
  std::string worst;
  for (const auto& name : candidates) {
    const Effect effect = *effect_from_name(name);
    if (!unsupported_reason(effect, base_).empty()) continue;
    const EffectKind& k = *effect.kind;
    if (k.search == Search::lattice) {
      // A lattice is seen in the levels themselves: any step at least twice the modelled resolution.
      const double r = std::max(k.material, 2.0 * sensors_.resolution_mm);
      d.thresholds.push_back({name, k.parameter, k.unit, kNaN, r});
      continue;
    }
    const Signature sig = signature_of(effect, model, base);
    const DetectionThreshold t = threshold_of(effect, sig, d.channels, o_.none_noise_factor);
    // How far the threshold lies beyond the smallest change of interest, on the worse side.
    double ratio = std::numeric_limits<double>::infinity();
    for (const double side : {t.below, t.above}) {
      if (std::isfinite(side)) ratio = std::min(ratio, std::abs(to_theta(effect, side) - k.theta_none) / k.material);
    }
    if (sig.ok && ratio > worst_ratio) {
      worst_ratio = ratio;
      worst = name;
      worst_energy = sig.energy;
    }
    d.thresholds.push_back(t);
  }
  if (worst.empty() || worst_energy.empty()) return;
  // The recording in which that effect shows most: recording longer there lowers its threshold
  // (the score's noise falls with the square root of the samples).
  const auto at = static_cast<std::size_t>(std::max_element(worst_energy.begin(), worst_energy.end()) - worst_energy.begin());
  d.lowering_experiment = "the largest threshold is " + worst + "'s; it shows most in " + recs_[at].name +
                          " (operating opening " + format_fixed(recs_[at].operating_point_mm, 1) +
                          " mm): a longer recording at that operating point, or a sensor on the channel it acts on, "
                          "lowers it";
}

}  // namespace canalsim::diagnosis::scenario_engine
