#include "diagnosis/report.hpp"

#include "core/json.hpp"
#include "core/format.hpp"
#include "core/html.hpp"
#include "plot/composites.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace canalsim::diagnosis {
namespace {

using nlohmann::json;


json correlation_json(const CorrelationTest& t) {
  return json{{"bound", t.bound}, {"outside", t.outside}, {"allowed", t.allowed}, {"pass", t.pass},
              {"lags", t.lags}, {"values", t.values}};
}

json mismatch_json(const Mismatch& m) {
  json windows = json::array();
  for (const auto& w : m.windows) {
    windows.push_back({{"recording", w.recording}, {"start_s", w.start_s}, {"end_s", w.end_s},
                       {"rms_mm", w.rms}, {"peak_mm", w.peak}, {"events", w.events}});
  }
  json by_recording = json::array();
  for (const auto& r : m.by_recording) {
    json channels = json::object();
    for (const auto& c : r.channels) channels[c.name] = {{"rms", c.rms}, {"mean", c.mean}};
    by_recording.push_back({{"recording", r.name}, {"operating_point_mm", r.operating_point_mm},
                            {"nrmse_percent", json_number(r.nrmse_percent)}, {"rms_mm", r.rms}, {"mean_mm", r.mean},
                            {"free_fraction", r.free_fraction < 0.0 ? json(nullptr) : json(r.free_fraction)},
                            {"white", r.white}, {"uncorrelated_with_input", r.uncorrelated}, {"channels", channels}});
  }
  auto groups = [](const std::vector<GroupStat>& g) {
    json out = json::object();
    for (const auto& x : g) out[x.name] = {{"samples", x.samples}, {"rms_mm", x.rms}, {"mean_mm", x.mean}};
    return out;
  };
  json by_channel = json::object();
  for (const auto& c : m.by_channel) by_channel[c.name] = {{"rms", c.rms}, {"mean", c.mean}};
  json band = m.band.found ? json::array({m.band.low_hz, m.band.high_hz}) : json(nullptr);
  return json{{"windows", windows}, {"band_hz", band}, {"by_recording", by_recording},
              {"by_regime", groups(m.by_regime)}, {"by_event", groups(m.by_event)},
              {"by_level", groups(m.by_level)}, {"by_channel", by_channel}};
}


}  // namespace

namespace {

json thresholds_json(const Diagnosis& d) {
  json out = json::array();
  for (const auto& t : d.thresholds) {
    out.push_back({{"effect", t.effect}, {"parameter", t.parameter}, {"unit", t.unit}, {"revealed_at_or_below", json_number(t.below)},
                   {"revealed_at_or_above", json_number(t.above)}});
  }
  return out;
}

// "≤ −0.31 or ≥ 0.29 mm", "≤ 12 mm/s", "not within the catalog's range".
// An effect's held-out score slower than 2 s, or "-" where the engine does not measure it.
std::string slow_score_text(const EffectResult& e) {
  return e.heldout_slow_cost_before > 0.0 ? format_figure(e.slow_score, 3) : "-";
}

std::string threshold_text(const DetectionThreshold& t) {
  std::string out;
  if (std::isfinite(t.below)) out += "<= " + format_g(t.below, 3);
  if (std::isfinite(t.above)) out += (out.empty() ? "" : " or ") + std::string(">= ") + format_g(t.above, 3);
  return out.empty() ? "not revealed within the catalog's range" : t.parameter + " " + out + " " + t.unit;
}

}  // namespace

json to_json(const Diagnosis& d) {
  json effects = json::array();
  for (const auto& e : d.effects) {
    json parameters = json::object();
    parameters[e.parameter.name] = {{"value", json_number(e.parameter.value)}, {"std", json_number(e.parameter.std)},
                                    {"unit", e.parameter.unit}};
    effects.push_back({{"name", e.name}, {"score", json_number(e.score)}, {"significant", e.significant},
                       {"material", e.material}, {"parameters", parameters},
                       {"nrmse_before", json_number(e.nrmse_before)}, {"nrmse_after", json_number(e.nrmse_after)},
                       {"heldout_nrmse_before", json_number(e.heldout_nrmse_before)},
                       {"heldout_nrmse_after", json_number(e.heldout_nrmse_after)},
                       {"cost_before", json_number(e.cost_before)}, {"cost_after", json_number(e.cost_after)},
                       {"heldout_cost_before", json_number(e.heldout_cost_before)},
                       {"heldout_cost_after", json_number(e.heldout_cost_after)},
                       {"slow_score", json_number(e.slow_score)},
                       {"heldout_slow_cost_before", json_number(e.heldout_slow_cost_before)},
                       {"heldout_slow_cost_after", json_number(e.heldout_slow_cost_after)}, {"delta_bic", json_number(e.delta_bic)},
                       {"simulations", e.simulations}, {"note", e.note},
                       {"heldout_improves", e.heldout_improves}, {"set_aside", e.set_aside}});
  }
  json tests = json::array();
  for (std::size_t i = 0; i < d.tests_before.size(); ++i) {
    json t{{"recording", i < d.series.size() ? d.series[i].name : std::to_string(i)},
           {"before", {{"autocorrelation", correlation_json(d.tests_before[i].autocorrelation)},
                       {"cross_correlation", correlation_json(d.tests_before[i].cross_correlation)}}}};
    if (i < d.tests_after.size()) {
      t["after"] = {{"autocorrelation", correlation_json(d.tests_after[i].autocorrelation)},
                    {"cross_correlation", correlation_json(d.tests_after[i].cross_correlation)}};
    }
    tests.push_back(t);
  }
  json scales = json::object();
  for (const auto& [c, s] : d.channel_scale) scales[c] = s;
  const auto parameter_json = [](const ParameterEstimate& p) {
    return json{{p.name, {{"value", json_number(p.value)}, {"std", json_number(p.std)}, {"unit", p.unit}}}};
  };
  json explanation = json::array();
  for (const auto& e : d.explanation) {
    explanation.push_back({{"name", e.name}, {"parameters", parameter_json(e.parameter)}, {"score", json_number(e.score)},
                           {"share", json_number(e.share)}});
  }
  json ambiguous = json::array();
  for (const auto& a : d.ambiguous) {
    ambiguous.push_back({{"effects", {a.first, a.second}},
                         {"estimates", {{a.first, parameter_json(a.first_parameter)[a.first_parameter.name]},
                                        {a.second, parameter_json(a.second_parameter)[a.second_parameter.name]}}},
                         {"scores", {json_number(a.first_score), json_number(a.second_score)}},
                         {"separating_experiment", a.separating_experiment}});
  }
  json channels = json::array();
  for (const auto& c : d.channels) {
    channels.push_back({{"name", c.name}, {"nominal_rms_mm", json_number(c.rms)}, {"noise_mm", json_number(c.noise)},
                        {"tolerated_mm", json_number(c.tolerated)}, {"slow_rms_mm", json_number(c.slow_rms)},
                        {"slow_tolerated_mm", json_number(c.slow_tolerated)}, {"ordinary", c.ordinary}});
  }
  // The candidates that scored above the verdict and why each was passed over.
  json passed_over = json::array();
  double verdict_score = 0.1;  // below this a candidate explains too little to be a contender
  for (const auto& e : d.effects) {
    if (e.name == d.verdict) verdict_score = std::max(verdict_score, e.score);
  }
  for (const auto& e : d.effects) {
    if (!e.significant && e.note.empty() && e.score > verdict_score) {
      passed_over.push_back({{"name", e.name}, {"score", json_number(e.score)}, {"why", e.set_aside}});
    }
  }
  json out{{"ok", d.ok}, {"verdict", d.verdict}, {"reason", d.reason}, {"explanation", explanation},
           {"channels", channels}, {"passed_over", passed_over}, {"thresholds", thresholds_json(d)},
           {"lowering_experiment", d.lowering_experiment},
           {"ambiguous", ambiguous}, {"effects", effects},
           {"mismatch", mismatch_json(d.mismatch)}, {"mismatch_after", mismatch_json(d.mismatch_after)},
           {"residual_tests", tests}, {"noise_mm", d.noise}, {"noise_limit_nrmse", json_number(d.noise_limit_nrmse)},
           {"nominal_rms_mm", d.nominal_rms}, {"channel_scale", scales}, {"seconds", d.seconds}};
  if (d.model_cells > 0) out["grid"] = {{"model_cells", d.model_cells}, {"search_cells", d.search_cells}};
  if (d.form) {
    json estimates = json::array();
    for (const auto& e : d.form->estimates) {
      estimates.push_back({{"recording", e.recording}, {"value", json_number(e.parameter.value)}, {"std", json_number(e.parameter.std)},
                           {"departure", json_number(e.departure)}, {"departure_std", json_number(e.departure_std)},
                           {"model_error", json_number(e.model_error)}, {"compared", e.compared}});
    }
    out["form"] = {{"effect", d.form->effect}, {"holds", d.form->holds},
                   {"relative_spread", json_number(d.form->relative_spread)}, {"per_recording", estimates}};
  }
  if (d.unexplained) {
    json models = json::array();
    for (const auto& m : d.unexplained->discrepancy) {
      models.push_back({{"channel", m.channel}, {"found", m.found}, {"form", m.form}, {"poles", m.poles},
                        {"numerator", m.numerator}, {"delay_s", json_number(m.delay_s)}, {"static_gain", json_number(m.static_gain)},
                        {"a", m.a}, {"b", m.b}, {"offsets_mm", m.offsets}, {"peak_hz", json_number(m.peak_hz)},
                        {"band_hz", {json_number(m.band_low_hz), json_number(m.band_high_hz)}},
                        {"heldout_rms_before_mm", json_number(m.heldout_rms_before)},
                        {"heldout_rms_after_mm", json_number(m.heldout_rms_after)},
                        {"heldout_share_removed", json_number(m.heldout_share_removed)},
                        {"offsets_share_removed", json_number(m.offsets_share_removed)}});
    }
    out["unexplained"] = {{"channel", d.unexplained->channel}, {"summary", d.unexplained->summary},
                          {"where", mismatch_json(d.unexplained->where)}, {"discrepancy_models", models}};
  }
  if (!d.ok) out["message"] = d.message;
  return out;
}

std::string text_summary(const Diagnosis& d) {
  std::ostringstream s;
  if (!d.ok) {
    s << "diagnosis failed: " << d.message << '\n';
    return s.str();
  }
  s << "verdict: " << d.verdict << "  (" << d.reason << ")\n";
  if (d.explanation.size() > 1) {
    s << "explanation:";
    for (const auto& e : d.explanation) {
      s << "  " << e.name << " (" << e.parameter.name << " " << format_estimate(e.parameter.value, e.parameter.std) << " "
        << e.parameter.unit << ", removes " << format_figure(100.0 * e.share, 0) << "%)";
    }
    s << '\n';
  }
  for (const auto& a : d.ambiguous) {
    s << "ambiguous: " << a.first << " (" << format_estimate(a.first_parameter.value, a.first_parameter.std) << " "
      << a.first_parameter.unit << ") or " << a.second << " (" << format_estimate(a.second_parameter.value, a.second_parameter.std)
      << " " << a.second_parameter.unit << ") explain the residual about equally; to tell them apart: "
      << a.separating_experiment << '\n';
  }
  s << "noise " << format_figure(d.noise, 3) << " mm, nominal residual RMS " << format_figure(d.nominal_rms, 3)
    << " mm, noise-limited Nrmse " << format_figure(d.noise_limit_nrmse, 1) << "%\n";
  for (const auto& c : d.channels) {
    s << "  " << c.name << ": nominal RMS " << format_figure(c.rms, 3) << " mm, noise " << format_figure(c.noise, 3) << " mm"
      << (c.tolerated > 0.0 ? ", tolerated " + format_figure(c.tolerated, 3) + " mm" : std::string())
      << (c.slow_tolerated > 0.0 ? "; slower than 2 s " + format_figure(c.slow_rms, 3) + " mm, tolerated " +
                                       format_figure(c.slow_tolerated, 3) + " mm"
                                 : std::string())
      << (c.ordinary ? "" : "  <- beyond noise and tolerance") << '\n';
  }
  if (d.search_cells > 0 && d.search_cells < d.model_cells) {
    s << "searches replayed on " << d.search_cells << " cells, corrected by the nominal model's difference from its "
      << d.model_cells << "; every judged point replayed on the " << d.model_cells << '\n';
  }
  if (d.form && d.form->holds) {
    s << d.form->effect << " fitted to each recording alone:";
    for (const auto& e : d.form->estimates) {
      s << "  " << e.recording << " " << format_estimate(e.parameter.value, e.parameter.std) << (e.compared ? "" : " (not compared)");
    }
    s << "  (one constant of the canal)\n";
  }
  if (d.unexplained) s << "where the unexplained residual lives: " << d.unexplained->summary << '\n';
  if (!d.thresholds.empty()) {
    s << "detection thresholds (what these recordings would reveal):\n";
    for (const auto& t : d.thresholds) s << "  " << t.effect << ": " << threshold_text(t) << '\n';
    if (!d.lowering_experiment.empty()) s << "  " << d.lowering_experiment << '\n';
  }
  const json document = to_json(d);  // kept alive: a range over a member of a temporary would dangle
  for (const auto& e : document["passed_over"]) {
    s << "set aside: " << e["name"].get<std::string>() << " (score " << format_figure(e["score"].is_number() ? e["score"].get<double>() : std::nan(""), 2)
      << "): " << e["why"].get<std::string>() << '\n';
  }
  s << '\n';
  // The name column fits the longest effect name (upstream_level_variation is 24 characters).
  int width = 22;
  for (const auto& e : d.effects) width = std::max(width, static_cast<int>(e.name.size()));
  char line[320];
  std::snprintf(line, sizeof line, "%-*s %7s %7s %4s %26s %9s %9s %9s %9s %8s\n", width, "effect", "score", "slow", "sig",
                "parameter", "Nrmse fit", "after", "held-out", "after", "dBIC");
  s << line;
  for (const auto& e : d.effects) {
    if (e.parameter.name.empty() && !e.note.empty()) {  // not tried: say why instead of zeros
      std::snprintf(line, sizeof line, "%-*s   -- ", width, e.name.c_str());
      s << line << e.note << '\n';
      continue;
    }
    const std::string p = format_estimate(e.parameter.value, e.parameter.std) + " " + e.parameter.unit;
    // An index that is not defined (Nrmse of a part whose levels do not vary) prints as "-".
    std::snprintf(line, sizeof line, "%-*s %7s %7s %4s %26s %9s %9s %9s %9s %8s\n", width, e.name.c_str(),
                  format_figure(e.score, 3).c_str(), slow_score_text(e).c_str(), e.significant ? "yes" : "", p.c_str(),
                  format_figure(e.nrmse_before, 2).c_str(),
                  format_figure(e.nrmse_after, 2).c_str(), format_figure(e.heldout_nrmse_before, 2).c_str(),
                  format_figure(e.heldout_nrmse_after, 2).c_str(), format_figure(e.delta_bic, 0).c_str());
    s << line;
  }
  s << "\nwhere the nominal residual lives:\n";
  if (d.mismatch.band.found) {
    s << "  band " << format_figure(d.mismatch.band.low_hz, 3) << "-" << format_figure(d.mismatch.band.high_hz, 3) << " Hz\n";
  } else {
    s << "  no frequency band where the input->residual model is significant\n";
  }
  for (const auto& r : d.mismatch.by_recording) {
    s << "  " << r.name << " (op " << format_figure(r.operating_point_mm, 1) << " mm): Nrmse " << format_figure(r.nrmse_percent, 2)
      << "%, RMS " << format_figure(r.rms, 3) << " mm, mean " << format_figure(r.mean, 3) << " mm" << (r.white ? "" : ", not white")
      << (r.uncorrelated ? "" : ", correlated with u") << '\n';
  }
  for (const auto& g : d.mismatch.by_regime) {
    if (g.samples) s << "  regime " << g.name << ": RMS " << format_figure(g.rms, 3) << " mm over " << g.samples << " samples\n";
  }
  for (std::size_t k = 0; k < d.mismatch.windows.size() && k < 5; ++k) {
    const auto& w = d.mismatch.windows[k];
    s << "  window " << w.recording << " " << format_figure(w.start_s, 1) << "-" << format_figure(w.end_s, 1) << " s: RMS "
      << format_figure(w.rms, 3) << " mm;";
    for (const auto& e : w.events) s << ' ' << e;
    s << '\n';
  }
  return s.str();
}

std::vector<plot::Figure> report_figures(const Diagnosis& d) {
  std::vector<plot::Figure> figures;
  if (!d.ok) return figures;
  // A clean diagnosis (`none`) has no mismatch to point at: its largest-residual windows are noise.
  const bool mismatch = d.verdict != "none";
  const bool corrected = d.verdict != "none" && d.verdict != "unexplained";
  for (std::size_t i = 0; i < d.series.size(); ++i) {
    const RecordingSeries& r = d.series[i];
    if (r.t.empty()) continue;
    plot::Comparison c;
    c.t = r.t;
    c.measured = {"recorded", r.recorded, "recorded"};
    c.models.push_back({"nominal", r.nominal, "nominal model"});
    if (corrected) c.models.push_back({"corrected", r.corrected, "corrected (" + d.verdict + ")"});
    if (mismatch) {
      for (const auto& w : d.mismatch.windows) {
        if (w.recording == r.name) c.windows.push_back({w.start_s, w.end_s});
      }
      c.window_label = "largest nominal residual";
    }
    if (r.fit_samples > 0 && r.fit_samples < r.t.size()) c.markers.push_back({r.t[r.fit_samples], "held-out →"});
    const std::string stem = plot::file_stem(r.name);
    c.name = stem + "_levels_and_residual";
    c.title = r.name + ": recorded level and models, residual below";
    figures.push_back(plot::measured_vs_model(c));
    const int lags = i < d.tests_before.size() && !d.tests_before[i].autocorrelation.lags.empty()
                         ? static_cast<int>(d.tests_before[i].autocorrelation.lags.size())
                         : 50;
    figures.push_back(plot::autocorrelation_figure(stem + "_residual_autocorrelation",
                                                   r.name + ": autocorrelation of the residual", plot::residuals(c), lags));
    c.name = stem + "_step_zoom";
    c.title = r.name + ": the response to the largest command change";
    if (auto zoom = plot::step_zoom(c, r.u, "mm")) figures.push_back(std::move(*zoom));
  }
  return figures;
}

std::string html_report(const Diagnosis& d, const std::string& title) {
  std::ostringstream s;
  s << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>" << html::escape(title)
    << "</title><style>body{font-family:sans-serif;max-width:960px;margin:auto;padding:1em}"
       "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
       "td:first-child,th:first-child{text-align:left}.sig{background:#e6f4e6}</style></head><body>";
  s << "<h1>" << html::escape(title) << "</h1>";
  if (!d.ok) {
    s << "<p>Diagnosis failed: " << html::escape(d.message) << "</p></body></html>\n";
    return s.str();
  }
  s << "<h2>Verdict: " << html::escape(d.verdict) << "</h2><p>" << html::escape(d.reason) << ".</p>";
  if (d.unexplained) {
    s << "<p>Where the unexplained residual lives: " << html::escape(d.unexplained->summary)
      << ". The discrepancy model describes the residual; it is not physics.</p>";
  }
  s << "<p>Measurement noise " << format_figure(d.noise, 3) << " mm; nominal residual RMS " << format_figure(d.nominal_rms, 3)
    << " mm; a perfect model would reach Nrmse " << format_figure(d.noise_limit_nrmse, 1) << "%.</p>";
  s << "<h2>Candidates</h2><table><tr><th>effect</th><th>score</th><th>score slower than 2 s</th><th>parameter</th><th>Nrmse fitted</th>"
       "<th>after</th><th>Nrmse held-out</th><th>after</th><th>&#916;BIC</th></tr>";
  for (const auto& e : d.effects) {
    s << "<tr" << (e.significant ? " class='sig'" : "") << "><td>" << html::escape(e.name) << "</td><td>" << format_figure(e.score, 3)
      << "</td><td>" << slow_score_text(e) << "</td><td>" << html::escape(e.parameter.name) << " = " << html::escape(format_estimate(e.parameter.value, e.parameter.std))
      << ' ' << html::escape(e.parameter.unit) << "</td><td>" << format_figure(e.nrmse_before, 2)
      << "</td><td>" << format_figure(e.nrmse_after, 2) << "</td><td>" << format_figure(e.heldout_nrmse_before, 2) << "</td><td>"
      << format_figure(e.heldout_nrmse_after, 2) << "</td><td>" << format_figure(e.delta_bic, 0) << "</td></tr>";
  }
  s << "</table>";
  if (!d.thresholds.empty()) {
    s << "<h2>What these recordings cannot show</h2><p>The smallest value of each effect's parameter that these "
         "recordings would reveal against the model under the same significance rule; effects smaller than these "
         "were not visible.</p><table><tr><th>effect</th><th>revealed when</th></tr>";
    for (const auto& t : d.thresholds) {
      s << "<tr><td>" << html::escape(t.effect) << "</td><td>" << html::escape(threshold_text(t)) << "</td></tr>";
    }
    s << "</table>";
    if (!d.lowering_experiment.empty()) s << "<p>" << html::escape(d.lowering_experiment) << ".</p>";
  }
  s << "<h2>Where the mismatch lives</h2><p>";
  if (d.mismatch.band.found) {
    s << "Input&#8594;residual model significant in " << format_figure(d.mismatch.band.low_hz, 3) << "&#8211;"
      << format_figure(d.mismatch.band.high_hz, 3) << " Hz";
  } else {
    s << "No frequency band where the input&#8594;residual model leaves its 99% region";
  }
  if (d.mismatch_after.band.found) {
    s << "; after the correction: " << format_figure(d.mismatch_after.band.low_hz, 3) << "&#8211;"
      << format_figure(d.mismatch_after.band.high_hz, 3) << " Hz.";
  } else {
    s << "; none after the correction.";
  }
  s << "</p><table><tr><th>recording</th><th>op [mm]</th><th>Nrmse before</th><th>after</th><th>RMS before</th>"
       "<th>after</th><th>white before/after</th></tr>";
  for (std::size_t i = 0; i < d.mismatch.by_recording.size(); ++i) {
    const auto& b = d.mismatch.by_recording[i];
    const auto& a = d.mismatch_after.by_recording[i];
    s << "<tr><td>" << html::escape(b.name) << "</td><td>" << format_figure(b.operating_point_mm, 1) << "</td><td>"
      << format_figure(b.nrmse_percent, 2) << "</td><td>" << format_figure(a.nrmse_percent, 2) << "</td><td>" << format_figure(b.rms, 3)
      << "</td><td>" << format_figure(a.rms, 3) << "</td><td>" << (b.white ? "yes" : "no") << " / " << (a.white ? "yes" : "no")
      << "</td></tr>";
  }
  s << "</table><p>By regime:";
  for (const auto& g : d.mismatch.by_regime) {
    if (g.samples) s << ' ' << html::escape(g.name) << " RMS " << format_figure(g.rms, 3) << " mm (" << g.samples << " samples);";
  }
  s << " by event:";
  for (const auto& g : d.mismatch.by_event) {
    if (g.samples) s << ' ' << html::escape(g.name) << ' ' << format_figure(g.rms, 3) << " mm;";
  }
  s << "</p>";
  s << "<h2 id='figures'>Recorded level, models and residuals</h2>";
  for (const auto& figure : report_figures(d)) s << plot::render_svg(figure) << '\n';
  s << "<p>Data and plots are inline; the page needs no network.</p></body></html>\n";
  return s.str();
}

}  // namespace canalsim::diagnosis
