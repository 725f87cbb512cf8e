#include "diagnosis/pipeline.hpp"

#include <algorithm>
#include <iterator>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>

#include "calibration/residual_breakdown.hpp"
#include "core/errors.hpp"
#include "diagnosis/catalog.hpp"
#include "core/format.hpp"

namespace canalsim::diagnosis {

namespace {

// The own score above which an effect that needs no re-simulation joins the explanation step.
constexpr double kReadingEffectScore = 0.02;

std::vector<ResidualTests> tests_of(const std::vector<RecordingResiduals>& sets, const ResidualTestOptions& o) {
  std::vector<ResidualTests> out;
  for (const auto& r : sets) out.push_back(residual_tests(r.residuals.at(r.primary), r.u, o));
  return out;
}

// Held-out scores within this share of the best are a tie: the recordings cannot prefer one
// effect to the other (an offset and a scale error of y_up_mm, which a PID-held reservoir keeps
// within a fraction of a millimetre, differ by 1e-4 of the score; on y_dw_mm, whose level differs
// by 16 mm between op1 and op3, a 4 % scale error beats the offset by 2 %).
constexpr double kTiedShare = 0.002;

// The catalog row of an effect name (its position in the table; past the end for the names of
// another engine's effects).
std::size_t row_of(const std::string& name) {
  const std::string kind = name.substr(0, name.find('['));
  const auto& rows = catalog();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (kind == rows[i].name) return i;
  }
  return rows.size();
}

// Among significant effects tied with the best (kTiedShare), the one listed first in the catalog
// leads: the table lists the plainer explanation first (an offset before a scale error on a
// sensor whose level hardly moves, a leak before a command that reads high). The tie itself is
// reported as an ambiguous pair (step 5).
void prefer_the_plainer_of_a_tie(std::vector<EffectResult>& effects) {
  if (effects.empty() || !effects.front().significant) return;
  std::size_t lead = 0;
  for (std::size_t i = 1; i < effects.size() && effects[i].significant; ++i) {
    if (effects.front().score - effects[i].score > kTiedShare * std::abs(effects.front().score)) break;
    if (row_of(effects[i].name) < row_of(effects[lead].name)) lead = i;
  }
  std::rotate(effects.begin(), effects.begin() + static_cast<std::ptrdiff_t>(lead), effects.begin() + static_cast<std::ptrdiff_t>(lead) + 1);
}

// Significant effects first, then those that could be evaluated, each group by held-out score;
// the plainer of a tie leads.
void rank(std::vector<EffectResult>& effects) {
  std::stable_sort(effects.begin(), effects.end(), [](const EffectResult& a, const EffectResult& b) {
    if (a.significant != b.significant) return a.significant;
    if (a.note.empty() != b.note.empty()) return a.note.empty();
    return a.score > b.score;
  });
  prefer_the_plainer_of_a_tie(effects);
}

// Step 5 of the pipeline (header): adds to the verdict, while one is significant, the remaining
// candidate that most improves the held-out fit when fitted jointly with the effects found so
// far; the explanation's parameters are those of the last joint fit.
void explain_with_several(Explainer& explainer, const PipelineSettings& settings, Diagnosis& d,
                          const std::function<void(const std::string&)>& progress) {
  const EffectResult& verdict = d.effects.front();
  d.explanation.push_back({verdict.name, verdict.parameter, verdict.score, verdict.score});
  // Every candidate the model can carry and that re-simulates the canal is tried, whatever its
  // own score: an effect of the hydraulics that counteracts the verdict's (an outflow beside a
  // leak) has none — fitted alone it sits at its bound — and shows only in a joint fit. An effect
  // of the readings alone (no re-simulation) is tried when it explains something by itself: a
  // sensor's fault does not hide behind the canal's physics, and a joint fit with a re-simulated
  // verdict costs a simulation per iteration.
  std::vector<std::string> remaining;
  for (std::size_t i = 1; i < d.effects.size(); ++i) {
    const EffectResult& e = d.effects[i];
    if (e.note.empty() && (e.simulations > 0 || e.score > kReadingEffectScore)) remaining.push_back(e.name);
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

// How far a channel's residual stands beyond what is ordinary for it, in total: a channel beyond
// its tolerance only in the slower part, where the model's error is small, would otherwise
// outrank the channel the residual is largest on. The verdict's reason and the location rank by it.
double excess(const ChannelFigures& c, double none_noise_factor) {
  return c.rms / std::max({none_noise_factor * c.noise, c.tolerated, 1e-12});
}

// The level channel furthest beyond what is ordinary for it (the primary when none is).
std::string furthest_channel(const Diagnosis& d, double none_noise_factor) {
  std::string out = d.channels.empty() ? "" : d.channels.front().name;
  double worst = 0.0;
  for (const auto& c : d.channels) {
    const double beyond = excess(c, none_noise_factor);
    if (!c.ordinary && beyond > worst) {
      worst = beyond;
      out = c.name;
    }
  }
  return out;
}

std::string largest_group(const std::vector<GroupStat>& all, const char* what) {
  std::vector<GroupStat> groups;  // a declared group no sample fell into says nothing
  std::copy_if(all.begin(), all.end(), std::back_inserter(groups), [](const GroupStat& g) { return g.samples > 0; });
  if (groups.size() < 2) return "";
  const auto top = std::max_element(groups.begin(), groups.end(), [](const GroupStat& a, const GroupStat& b) { return a.rms < b.rms; });
  std::string out = std::string("largest ") + what + " " + top->name + " (RMS " + format_fixed(top->rms, 3) + " mm";
  for (const auto& g : groups) {
    if (&g != &*top) out += "; " + g.name + " " + format_fixed(g.rms, 3) + " mm";
  }
  return out + ")";
}

std::string describe_discrepancy(const DiscrepancyModel& m) {
  if (m.found) {
    return "a " + m.form + " discrepancy model (" + std::to_string(m.poles) + " pole(s), static gain " +
           format_g(m.static_gain, 3) + " mm per mm of command, delay " + format_fixed(m.delay_s, 2) + " s, band " +
           format_fixed(m.band_low_hz, 3) + "-" + format_fixed(m.band_high_hz, 3) + " Hz) removes " +
           format_fixed(100.0 * m.heldout_share_removed, 0) + " % of the held-out residual";
  }
  if (m.form == "static") {
    return "a constant per operating point removes " + format_fixed(100.0 * m.offsets_share_removed, 0) +
           " % of the held-out residual: a static error that does not follow the command";
  }
  return "no low-order filter from the command explains it: it does not follow the command (a drift, a disturbance)";
}

// Where an unexplained residual lives, and a discrepancy model for every level channel.
UnexplainedResidual locate_unexplained(const std::vector<RecordingResiduals>& sets, const Diagnosis& d,
                                       const PipelineSettings& settings) {
  UnexplainedResidual u;
  u.channel = furthest_channel(d, settings.none_noise_factor);
  std::vector<RecordingResiduals> on = sets;
  for (auto& r : on) {
    if (const auto it = r.recorded.find(u.channel); it != r.recorded.end()) r.level = it->second;
    if (r.residuals.count(u.channel)) r.primary = u.channel;
  }
  u.where = locate(on, settings.locate);
  for (const auto& c : d.channels) {
    std::vector<DiscrepancyRecording> records;
    for (const auto& r : sets) {
      const auto e = r.residuals.find(c.name);
      if (e == r.residuals.end() || r.u.size() != e->second.size() || e->second.size() < 8) continue;
      const std::size_t n_fit = r.fit_samples > 0 && r.fit_samples < e->second.size() ? r.fit_samples : e->second.size() / 2;
      records.push_back({r.u, e->second, n_fit});
    }
    if (!records.empty()) u.discrepancy.push_back(fit_discrepancy(c.name, records, sets.front().period_s));
  }
  // In words.
  std::string text = "on " + u.channel;
  for (const auto& c : d.channels) {
    if (c.name == u.channel) text += " (RMS " + format_fixed(c.rms, 3) + " mm, noise " + format_fixed(c.noise, 3) + " mm)";
  }
  if (const std::string regime = largest_group(u.where.by_regime, "in"); !regime.empty()) text += "; " + regime;
  if (!u.where.by_recording.empty()) {
    const auto top = std::max_element(u.where.by_recording.begin(), u.where.by_recording.end(),
                                      [](const RecordingStat& a, const RecordingStat& b) { return a.rms < b.rms; });
    text += "; largest in " + top->name + " (operating opening " + format_fixed(top->operating_point_mm, 1) + " mm, RMS " +
            format_fixed(top->rms, 3) + " mm)";
  }
  if (!u.where.windows.empty()) {
    const MismatchWindow& w = u.where.windows.front();
    text += "; worst window " + w.recording + " " + format_fixed(w.start_s, 1) + "-" + format_fixed(w.end_s, 1) + " s";
    for (const auto& e : w.events) text += " " + e;
  }
  if (u.where.band.found) text += "; band " + format_fixed(u.where.band.low_hz, 3) + "-" + format_fixed(u.where.band.high_hz, 3) + " Hz";
  for (const auto& m : u.discrepancy) {
    if (m.channel == u.channel) text += "; " + describe_discrepancy(m);
  }
  u.summary = text;
  return u;
}

// "op1 0.117 ± 0.002, op3 0.349 ± 0.003"
std::string list_estimates(const FormCheck& f) {
  std::string out;
  for (const auto& e : f.estimates) {
    if (e.compared) out += (out.empty() ? "" : ", ") + e.recording + " " + format_estimate(e.parameter.value, e.parameter.std);
  }
  return out;
}

// "its fraction_of_inflow differs between them (op1 0.117 ± 0.002, op3 0.349 ± 0.003)", and the
// recordings left out of the comparison.
std::string differs(const EffectResult& e, const FormCheck& f) {
  std::string left_out;
  for (const auto& r : f.estimates) {
    if (!r.compared) left_out += (left_out.empty() ? "" : ", ") + r.recording;
  }
  return "fitted to each recording alone its " + e.parameter.name + " differs between them (" + list_estimates(f) +
         (e.parameter.unit == std::string("-") ? "" : " " + e.parameter.unit) + ")" +
         (left_out.empty() ? "" : "; not compared, where the model's error could move it further than the effect: " + left_out);
}

// Step 5, when the verdict's form does not hold: it explains the residual, but not as one
// constant of the canal — the physics has another form than the catalog's row (a seepage that
// grows with the depth fitted as a constant share of the inflow). The verdict is `unexplained`,
// whatever the channels' figures; the row stays in d.effects and d.form as the nearest the
// catalog has.
void set_verdict_outside_catalog(Diagnosis& d, const EffectResult& nearest) {
  d.reason = nearest.name + " reduces the held-out cost by " + format_g(std::round(100.0 * nearest.score)) + "%, but " +
             differs(nearest, *d.form) +
             " far beyond what the model's error moves it: not one constant of the canal, so the physics is not in "
             "the catalog (" + nearest.name + " is its nearest row)";
  d.verdict = "unexplained";
}

// Step 5, for a verdict that explains alone (an explanation of one effect): its form across the
// recordings. When it does not hold, the effect is set aside (`set_aside` says why) and the
// verdict is `unexplained` with it as the nearest row. An effect of an explanation of several is
// not checked alone: fitted without the others, its parameter takes up theirs, which differ
// between operating points (a leak beside a downstream gate set lower). Returns whether the
// verdict stands.
bool verdict_form_holds(Explainer& explainer, const PipelineSettings& settings, Diagnosis& d,
                        const std::function<void(double, const std::string&)>& progress) {
  if (d.explanation.size() != 1) return true;
  progress(0.95, "form of " + d.verdict + " across the recordings");
  d.form = check_form(d.verdict, explainer.per_recording_estimates(d.verdict), settings);
  if (!d.form || d.form->holds) return true;
  EffectResult& nearest = d.effects.front();
  nearest.significant = false;
  nearest.set_aside = differs(nearest, *d.form) + ": not one constant of the canal";
  set_verdict_outside_catalog(d, nearest);
  d.explanation.clear();
  d.ambiguous.clear();
  return false;
}

// Whether the level channels that are not ordinary are so only in their part slower than the
// fast band: within the noise or the calibration's tolerance in total.
bool only_slower_part_beyond(const Diagnosis& d, double none_noise_factor) {
  bool any = false;
  for (const auto& c : d.channels) {
    if (c.ordinary) continue;
    if (!ordinary_in_total(c, c.rms, none_noise_factor)) return false;
    any = true;
  }
  return any;
}

// Step 4, when a level channel is beyond what the calibration tolerates only in its part slower
// than the fast band. There a calibrated model's own error is small (it is a bore placed
// differently within a sample), while a change of the canal moves the levels over the command's
// slower swings; in total, the model's error dominates every candidate's held-out score. The
// candidates are then judged on that part: the verdict is the best one that passes the
// significance rule on it and leaves every level channel ordinary, which is what the nominal
// model did not. Every other candidate's `set_aside` says how it fared there. Returns whether one
// is the verdict.
bool explained_slower_than_fast_band(Explainer& explainer, const PipelineSettings& settings, Diagnosis& d) {
  if (!only_slower_part_beyond(d, settings.none_noise_factor)) return false;
  std::vector<std::size_t> passing;
  for (std::size_t i = 0; i < d.effects.size(); ++i) {
    EffectResult& e = d.effects[i];
    if (!e.note.empty()) continue;
    if (is_significant(e, settings.significance, true)) {
      passing.push_back(i);
    } else if (e.slow_score < settings.significance.min_score) {
      e.set_aside += "; slower than 2 s, held-out score " + format_g(e.slow_score, 2) + " < " +
                     format_g(settings.significance.min_score);
    }
  }
  std::stable_sort(passing.begin(), passing.end(),
                   [&](std::size_t a, std::size_t b) { return d.effects[a].slow_score > d.effects[b].slow_score; });
  std::optional<std::size_t> named;
  for (std::size_t i : passing) {
    EffectResult& e = d.effects[i];
    if (named) {
      e.set_aside += "; slower than 2 s, held-out score " + format_g(e.slow_score, 2) + " below the verdict's " +
                     format_g(d.effects[*named].slow_score, 2);
      continue;
    }
    Diagnosis left;
    set_noise_figures(explainer.residuals_with(e.name), explainer.sensor_resolution(), settings, left);
    const auto beyond = std::find_if(left.channels.begin(), left.channels.end(), [](const ChannelFigures& c) { return !c.ordinary; });
    if (beyond != left.channels.end()) {
      e.set_aside += "; slower than 2 s it leaves " + beyond->name + " beyond what the calibration tolerates";
      continue;
    }
    named = i;
    e.significant = true;
    e.set_aside.clear();
    d.verdict = e.name;
    d.reason = e.name + " reduces the held-out cost slower than 2 s, where the model's own error is small, by " +
               format_g(std::round(100.0 * e.slow_score)) + "% (in total by " + format_g(std::round(100.0 * e.score)) +
               "%) and leaves every level channel within what the calibration tolerates (" + e.parameter.name + " = " +
               format_g(e.parameter.value) + " " + e.parameter.unit + ")";
  }
  if (!named) return false;
  std::rotate(d.effects.begin(), d.effects.begin() + static_cast<std::ptrdiff_t>(*named),
              d.effects.begin() + static_cast<std::ptrdiff_t>(*named) + 1);
  return true;
}

}  // namespace

std::optional<FormCheck> check_form(const std::string& effect, std::vector<RecordingEstimate> estimates,
                                    const PipelineSettings& settings) {
  const bool all_finite = std::all_of(estimates.begin(), estimates.end(), [](const RecordingEstimate& e) {
    return std::isfinite(e.departure) && std::isfinite(e.departure_std) && std::isfinite(e.model_error);
  });
  if (estimates.size() < 2 || !all_finite) return std::nullopt;
  FormCheck f;
  f.effect = effect;
  f.estimates = std::move(estimates);
  double size = 0.0;  // the mean departure's magnitude: estimates of both signs have one too
  for (const auto& e : f.estimates) size += std::abs(e.departure) / static_cast<double>(f.estimates.size());
  std::vector<const RecordingEstimate*> compared;
  for (auto& e : f.estimates) {
    e.compared = e.model_error < settings.form_compared * size;
    if (e.compared) compared.push_back(&e);
  }
  if (compared.size() < 2) {  // too few recordings show the effect above the model's error to judge its form
    f.relative_spread = std::numeric_limits<double>::quiet_NaN();
    return f;
  }
  const auto [low, high] = std::minmax_element(compared.begin(), compared.end(), [](const auto* a, const auto* b) {
    return a->departure < b->departure;
  });
  double compared_mean = 0.0;
  for (const auto* e : compared) compared_mean += e->departure / static_cast<double>(compared.size());
  const double spread = (*high)->departure - (*low)->departure;
  f.relative_spread = compared_mean != 0.0 ? spread / std::abs(compared_mean) : std::numeric_limits<double>::quiet_NaN();
  const double spread_std = std::hypot((*low)->departure_std, (*high)->departure_std);
  f.holds = !(spread > settings.form_spread * std::abs(compared_mean) && spread > settings.form_z * spread_std &&
              spread > settings.form_model_error * ((*low)->model_error + (*high)->model_error));
  return f;
}

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
    set_noise_figures(before, explainer.sensor_resolution(), settings, d);
    explainer.describe(d);

    for (std::size_t i = 0; i < candidates.size(); ++i) {
      progress(0.1 + 0.85 * static_cast<double>(i) / static_cast<double>(candidates.size()), candidates[i]);
      d.effects.push_back(explainer.explain(candidates[i]));
    }
    rank(d.effects);
    std::string corrected = set_verdict(d, settings.none_noise_factor) ? d.verdict : "";
    if (d.verdict == "unexplained" && explained_slower_than_fast_band(explainer, settings, d)) corrected = d.verdict;
    if (!corrected.empty()) {
      explain_with_several(explainer, settings, d,
                           [&](const std::string& candidate) { progress(0.95, "explanation: " + candidate); });
      if (!verdict_form_holds(explainer, settings, d, progress)) corrected.clear();
    }
    if (d.verdict == "unexplained") d.unexplained = locate_unexplained(before, d, settings);
    const auto after = explainer.residuals_with(corrected);
    if (!corrected.empty()) {
      // What the explanation leaves: when a level channel is still beyond its noise and the
      // calibration's tolerance, the rest is located as an unexplained residual (partly explained).
      Diagnosis left;
      set_noise_figures(after, explainer.sensor_resolution(), settings, left);
      if (std::any_of(left.channels.begin(), left.channels.end(), [](const ChannelFigures& c) { return !c.ordinary; })) {
        d.unexplained = locate_unexplained(after, left, settings);
        d.unexplained->summary = "left after " + corrected + " " + d.unexplained->summary;
      }
    }
    d.mismatch_after = locate(after, settings.locate);
    d.tests_after = tests_of(after, settings.tests);
    d.series = explainer.series_with(corrected);
    progress(0.97, "detection thresholds");
    explainer.detection_thresholds(candidates, corrected, d);
    if (d.verdict == "none" && !d.thresholds.empty()) {
      d.reason += "; effects smaller than their detection thresholds were not visible in these recordings";
    }
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

bool is_significant(const EffectResult& e, const SignificanceRule& rule, bool slower_part) {
  return e.material && (slower_part ? e.slow_score : e.score) >= rule.min_score && -e.delta_bic >= rule.min_bic_gain &&
         (!rule.heldout_fit_must_improve || e.heldout_improves);
}

namespace {

// One level channel's figures over every recording: its noise (each recording's estimate from the
// recorded series, pooled in quadrature), the nominal residual's RMS in total and in the part
// slower than the fast band, and what the noise leaves of that part (white noise averaged over
// the band's window of samples).
struct ChannelMeasures {
  ChannelFigures figures;
  double slow_noise = 0.0;
};

ChannelMeasures channel_measures(const std::vector<RecordingResiduals>& sets, const std::string& channel, double resolution) {
  ChannelMeasures m;
  ChannelFigures& f = m.figures;
  f.name = channel;
  double noise_sq = 0.0, slow_noise_sq = 0.0, rms_sq = 0.0, slow_sq = 0.0;
  std::size_t n = 0, recordings = 0;
  for (const auto& r : sets) {
    const auto e = r.residuals.find(channel);
    if (e == r.residuals.end()) continue;
    const auto y = r.recorded.find(channel);
    const std::vector<double>& recorded = y != r.recorded.end() ? y->second : r.level;
    const double sigma = noise_level(recorded, resolution);
    noise_sq += sigma * sigma;
    slow_noise_sq += sigma * sigma * r.period_s / calibration::fast_band_edge_s;
    ++recordings;
    rms_sq += std::inner_product(e->second.begin(), e->second.end(), e->second.begin(), 0.0);
    for (double v : calibration::slower_than_fast_band(e->second, r.period_s)) slow_sq += v * v;
    n += e->second.size();
  }
  const auto per_recording = static_cast<double>(std::max<std::size_t>(recordings, 1));
  const auto per_sample = static_cast<double>(std::max<std::size_t>(n, 1));
  f.noise = std::sqrt(noise_sq / per_recording);
  f.rms = std::sqrt(rms_sq / per_sample);
  f.slow_rms = std::sqrt(slow_sq / per_sample);
  m.slow_noise = std::sqrt(slow_noise_sq / per_recording);
  return m;
}

std::string mm(double v) { return format_fixed(v, 3) + " mm"; }

// "y_up_mm RMS 2.03 mm (noise 0.05 mm, tolerated 0.54 mm)"
std::string describe(const ChannelFigures& c) {
  const bool slow_beyond = c.slow_tolerated > 0.0 && c.slow_rms > c.slow_tolerated;
  return c.name + " RMS " + mm(c.rms) + " (noise " + mm(c.noise) +
         (c.tolerated > 0.0 ? ", tolerated " + mm(c.tolerated) : std::string()) +
         (slow_beyond ? "; slower than 2 s " + mm(c.slow_rms) + ", tolerated " + mm(c.slow_tolerated) : std::string()) + ")";
}

}  // namespace

bool DetectionThreshold::reveals(double value) const {
  return (std::isfinite(below) && value <= below) || (std::isfinite(above) && value >= above);
}

std::string set_aside_reason(const EffectResult& e, const SignificanceRule& rule) {
  std::vector<std::string> why;
  if (!e.material) {
    why.push_back("not material (" + e.parameter.name + " " + format_g(e.parameter.value, 3) +
                  " within the smallest change of interest, the calibrated model's own error or what the calibration "
                  "leaves open)");
  }
  if (e.score < rule.min_score) why.push_back("held-out score " + format_g(e.score, 2) + " < " + format_g(rule.min_score));
  if (-e.delta_bic < rule.min_bic_gain) {
    why.push_back("BIC gain " + format_g(-e.delta_bic, 3) + " < " + format_g(rule.min_bic_gain));
  }
  if (rule.heldout_fit_must_improve && !e.heldout_improves) {
    why.push_back(e.worsened.empty() ? std::string("the held-out fit does not improve")
                                     : "the held-out fit of " + e.worsened + " gets worse");
  }
  std::string out;
  for (const auto& w : why) out += (out.empty() ? "" : "; ") + w;
  return out;
}

void set_noise_figures(const std::vector<RecordingResiduals>& sets, double resolution, const PipelineSettings& settings,
                       Diagnosis& d) {
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

  // Every level channel the recordings carry, the primary first.
  std::vector<std::string> names;
  if (!sets.empty()) names.push_back(sets.front().primary);
  for (const auto& r : sets) {
    for (const auto& [channel, e] : r.residuals) {
      const bool level = channel == r.primary || r.recorded.count(channel) > 0;
      if (level && std::find(names.begin(), names.end(), channel) == names.end()) names.push_back(channel);
    }
  }
  d.channels.clear();
  for (const auto& name : names) {
    const ChannelMeasures m = channel_measures(sets, name, resolution);
    ChannelFigures f = m.figures;
    const auto own = settings.tolerated_by_channel.find(name);
    f.tolerated = own != settings.tolerated_by_channel.end() ? own->second : settings.tolerated_rms;
    const auto slow = settings.tolerated_slow_by_channel.find(name);
    if (slow != settings.tolerated_slow_by_channel.end()) {
      f.slow_tolerated = std::max(slow->second, settings.none_noise_factor * m.slow_noise);
    }
    f.ordinary = is_ordinary(f, f.rms, f.slow_rms, settings.none_noise_factor);
    d.channels.push_back(std::move(f));
  }
}

bool is_ordinary(const ChannelFigures& f, double rms, double slow_rms, double none_noise_factor) {
  // Within the noise, the residual is ordinary whatever its parts. Within the model's error, it
  // must be so in the slower part too.
  const bool within_model_error =
      f.tolerated > 0.0 && rms <= f.tolerated && (f.slow_tolerated == 0.0 || slow_rms <= f.slow_tolerated);
  return rms <= none_noise_factor * f.noise || within_model_error;
}

bool ordinary_in_total(const ChannelFigures& f, double rms, double none_noise_factor) {
  return rms <= none_noise_factor * f.noise || (f.tolerated > 0.0 && rms <= f.tolerated);
}

bool set_verdict(Diagnosis& d, double none_noise_factor) {
  if (!d.effects.empty() && d.effects.front().significant) {
    const EffectResult& w = d.effects.front();
    d.verdict = w.name;
    d.reason = w.name.rfind("sensor_quantization", 0) == 0
                   ? "the held-out levels lie on a " + format_g(w.parameter.value) + " mm lattice (coherence " +
                         format_g(std::round(100.0 * w.score) / 100.0) + ")"
                   : w.name + " reduces the held-out cost by " + format_g(std::round(100.0 * w.score)) + "% (" +
                         w.parameter.name + " = " + format_g(w.parameter.value) + " " + w.parameter.unit + ")";
    return true;
  }
  // The primary channel is also ordinary when its residual passes the residual tests (white and
  // uncorrelated with the input: nothing a model could still explain).
  const bool primary_white = std::all_of(d.tests_before.begin(), d.tests_before.end(),
                                         [](const ResidualTests& t) { return t.white() && t.uncorrelated(); });
  const ChannelFigures* unusual = nullptr;
  for (const auto& c : d.channels) {
    const bool ordinary = c.ordinary || (&c == &d.channels.front() && primary_white);
    if (!ordinary && (!unusual || excess(c, none_noise_factor) > excess(*unusual, none_noise_factor))) {
      unusual = &c;
    }
  }
  if (!unusual) {
    d.verdict = "none";
    const bool white_beyond_noise = !d.channels.empty() && !d.channels.front().ordinary;
    std::string figures;
    for (const auto& c : d.channels) {
      if (!white_beyond_noise || &c != &d.channels.front()) figures += (figures.empty() ? "" : "; ") + describe(c);
    }
    if (white_beyond_noise) {
      // Beyond the noise estimate, yet white and uncorrelated with the command: isolated outliers
      // or a noise the estimate misses, nothing a model of the canal or its instruments explains.
      d.reason = "the nominal residual on " + describe(d.channels.front()) +
                 " exceeds the noise but is white and uncorrelated with the command (outliers or unmodelled noise, "
                 "nothing a model could still explain)" +
                 (figures.empty() ? std::string() : "; the other level channels are ordinary (" + figures + ")") +
                 ", and no candidate improves the held-out fit";
      return false;
    }
    d.reason = "the nominal residual is within " + format_g(none_noise_factor) +
               " x the noise or what the calibration leaves on its baseline on every level channel (in total and, "
               "against a calibration, slower than 2 s: " + figures + ") and no candidate improves the held-out fit";
  } else {
    d.verdict = "unexplained";
    const bool total_beyond = !ordinary_in_total(*unusual, unusual->rms, none_noise_factor);
    const std::string beyond = total_beyond ? format_g(none_noise_factor) + " x the noise" +
                                                  (unusual->tolerated > 0.0 ? " and what the calibration tolerates" : "")
                                            : "what the calibration tolerates in its part slower than 2 s";
    d.reason = "the nominal residual on " + describe(*unusual) + " exceeds " + beyond +
               ", and no candidate improves the held-out fit significantly";
  }
  return false;
}

}  // namespace canalsim::diagnosis
