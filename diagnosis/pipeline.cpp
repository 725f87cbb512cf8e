#include "diagnosis/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <numeric>
#include <optional>

#include "core/errors.hpp"
#include "diagnosis/catalog.hpp"
#include "core/format.hpp"

namespace canalsim::diagnosis {

namespace {

std::vector<ResidualTests> tests_of(const std::vector<RecordingResiduals>& sets, const ResidualTestOptions& o) {
  std::vector<ResidualTests> out;
  for (const auto& r : sets) out.push_back(residual_tests(r.residuals.at(r.primary), r.u, o));
  return out;
}

// Step 5 of the pipeline (header): adds to the verdict, while one is significant, the remaining
// candidate that most improves the held-out fit when fitted jointly with the effects found so
// far; the explanation's parameters are those of the last joint fit.
void explain_with_several(Explainer& explainer, const PipelineSettings& settings, Diagnosis& d,
                          const std::function<void(const std::string&)>& progress) {
  const EffectResult& verdict = d.effects.front();
  d.explanation.push_back({verdict.name, verdict.parameter, verdict.score, verdict.score});
  // Every candidate the model can carry is tried, whatever its own score: an effect that
  // counteracts the verdict's (an outflow beside a leak) has none — fitted alone it sits at its
  // bound — and shows only in a joint fit.
  std::vector<std::string> remaining;
  for (std::size_t i = 1; i < d.effects.size(); ++i) {
    if (d.effects[i].note.empty()) remaining.push_back(d.effects[i].name);
  }
  std::map<std::string, JointExplanation> with_verdict;
  while (static_cast<int>(d.explanation.size()) < settings.max_effects && !remaining.empty()) {
    std::optional<JointExplanation> best;
    for (const auto& name : remaining) {
      progress(name);
      std::optional<JointExplanation> joint = explainer.explain_jointly(d.explanation, name);
      if (!joint) return;  // the engine cannot explain with several effects
      if (d.explanation.size() == 1) with_verdict[name] = *joint;
      if (joint->added.significant && (!best || joint->added.score > best->added.score)) best = std::move(joint);
    }
    if (!best) break;
    remaining.erase(std::find(remaining.begin(), remaining.end(), best->added.name));
    double left = 1.0;  // share of the nominal held-out cost the explanation leaves
    for (const auto& e : d.explanation) left *= 1.0 - std::clamp(e.score, 0.0, 1.0);
    for (std::size_t i = 0; i < d.explanation.size(); ++i) d.explanation[i].parameter = best->refitted.at(i);
    const EffectResult& added = best->added;
    d.explanation.push_back({added.name, added.parameter, added.score, left * std::clamp(added.score, 0.0, 1.0)});
  }
  // Ambiguity: a significant runner-up that adds nothing on top of the verdict, while the verdict
  // adds nothing on top of it either — each explains what the other does.
  for (std::size_t i = 1; i < d.effects.size(); ++i) {
    const EffectResult& r = d.effects[i];
    if (!r.significant || r.score < settings.ambiguity_share * verdict.score) continue;
    const auto joint = with_verdict.find(r.name);
    const bool adds = std::any_of(d.explanation.begin(), d.explanation.end(),
                                  [&](const ExplainedEffect& e) { return e.name == r.name; });
    if (adds || joint == with_verdict.end() || joint->second.added.significant || joint->second.explanation_adds) continue;
    d.ambiguous.push_back({verdict.name, r.name, verdict.parameter, r.parameter, verdict.score, r.score,
                           separating_experiment(verdict.name, r.name)});
  }
}

}  // namespace

Diagnosis run_pipeline(Explainer& explainer, const std::vector<std::string>& candidates,
                       const PipelineSettings& settings) {
  const auto started = std::chrono::steady_clock::now();
  const auto progress = [&](double fraction, const std::string& stage) {
    if (settings.progress) settings.progress({fraction, stage});
  };
  Diagnosis d;
  try {
    progress(0.0, "nominal");
    const auto before = explainer.nominal_residuals();
    d.mismatch = locate(before, settings.locate);
    d.tests_before = tests_of(before, settings.tests);
    set_noise_figures(before, explainer.sensor_resolution(), d);
    explainer.describe(d);

    for (std::size_t i = 0; i < candidates.size(); ++i) {
      progress(0.1 + 0.85 * static_cast<double>(i) / static_cast<double>(candidates.size()), candidates[i]);
      d.effects.push_back(explainer.explain(candidates[i]));
    }
    std::stable_sort(d.effects.begin(), d.effects.end(), [](const EffectResult& a, const EffectResult& b) {
      if (a.significant != b.significant) return a.significant;
      if (a.note.empty() != b.note.empty()) return a.note.empty();
      return a.score > b.score;
    });
    const std::string corrected = set_verdict(d, settings.none_noise_factor, settings.tolerated_rms) ? d.verdict : "";
    if (!corrected.empty()) {
      explain_with_several(explainer, settings, d,
                           [&](const std::string& candidate) { progress(0.95, "explanation: " + candidate); });
    }
    const auto after = explainer.residuals_with(corrected);
    d.mismatch_after = locate(after, settings.locate);
    d.tests_after = tests_of(after, settings.tests);
    d.series = explainer.series_with(corrected);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    d.ok = false;
    d.message = e.what();
  }
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  progress(1.0, "done");
  return d;
}

double bic_change(double n_eff, double cost_before, double cost_after, int extra_parameters) {
  return n_eff * std::log(std::max(cost_after, 1e-300) / std::max(cost_before, 1e-300)) +
         extra_parameters * std::log(n_eff);
}

bool is_significant(const EffectResult& e, const SignificanceRule& rule) {
  return e.material && e.score >= rule.min_score && -e.delta_bic >= rule.min_bic_gain &&
         (!rule.heldout_nrmse_must_rise || e.heldout_nrmse_after > e.heldout_nrmse_before);
}

void set_noise_figures(const std::vector<RecordingResiduals>& sets, double resolution, Diagnosis& d) {
  double noise_sq = 0.0, rms_sq = 0.0, spread_sq = 0.0;
  std::size_t n = 0;
  for (const auto& r : sets) {
    const double sigma = noise_level(r.level, resolution);
    noise_sq += sigma * sigma;
    const auto& e = r.residuals.at(r.primary);
    rms_sq += std::inner_product(e.begin(), e.end(), e.begin(), 0.0);
    n += e.size();
    const double mean = std::accumulate(r.level.begin(), r.level.end(), 0.0) / static_cast<double>(r.level.size());
    double v = 0.0;
    for (double y : r.level) v += (y - mean) * (y - mean);
    spread_sq += v / static_cast<double>(r.level.size());
  }
  const auto count = static_cast<double>(std::max<std::size_t>(sets.size(), 1));
  d.noise = std::sqrt(noise_sq / count);
  d.nominal_rms = std::sqrt(rms_sq / static_cast<double>(std::max<std::size_t>(n, 1)));
  d.noise_limit_nrmse = 100.0 * (1.0 - d.noise / std::sqrt(std::max(spread_sq / count, 1e-300)));
}

bool set_verdict(Diagnosis& d, double none_noise_factor, double tolerated_rms) {
  const bool ordinary = tolerated_rms > 0.0 && d.nominal_rms <= tolerated_rms;
  const bool within_noise = d.nominal_rms <= none_noise_factor * d.noise || ordinary ||
                            std::all_of(d.tests_before.begin(), d.tests_before.end(),
                                        [](const ResidualTests& t) { return t.white() && t.uncorrelated(); });
  if (!d.effects.empty() && d.effects.front().significant) {
    const EffectResult& w = d.effects.front();
    d.verdict = w.name;
    d.reason = w.name == "sensor_quantization"
                   ? "the held-out levels lie on a " + format_g(w.parameter.value) + " mm lattice (coherence " +
                         format_g(std::round(100.0 * w.score) / 100.0) + ")"
                   : w.name + " reduces the held-out cost by " + format_g(std::round(100.0 * w.score)) + "% (" +
                         w.parameter.name + " = " + format_g(w.parameter.value) + " " + w.parameter.unit + ")";
    return true;
  }
  if (within_noise) {
    d.verdict = "none";
    d.reason = ordinary && d.nominal_rms > none_noise_factor * d.noise
                   ? "the nominal residual (RMS " + format_g(d.nominal_rms) + " mm) is within what the calibration leaves on "
                         "its baseline (" + format_g(tolerated_rms) + " mm) and no candidate improves the held-out fit"
                   : "the nominal residual (RMS " + format_g(d.nominal_rms) + " mm) is within the measurement noise (" +
                         format_g(d.noise) + " mm) and no candidate improves the held-out fit";
  } else {
    d.verdict = "unexplained";
    d.reason = "the nominal residual (RMS " + format_g(d.nominal_rms) + " mm) exceeds " + format_g(none_noise_factor) +
               " x the noise (" + format_g(d.noise) + " mm) and no candidate improves the held-out fit significantly";
  }
  return false;
}

}  // namespace canalsim::diagnosis
