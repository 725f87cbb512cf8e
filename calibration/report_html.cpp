// The HTML report of a calibration: one self-contained page (inline SVG and CSS, no scripts or
// external resources), so it opens offline and can be mailed.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "calibration/report.hpp"
#include "calibration/time_offset.hpp"

#include "core/html.hpp"
#include "core/format.hpp"
#include "plot/composites.hpp"
#include "plot/palette.hpp"

namespace canalsim::calibration {
namespace {


// Amplitude spectrum |DFT| of a residual at 120 log-spaced frequencies between 1/T and the
// Nyquist frequency (direct sums: a few hundred thousand operations per series).
plot::Series spectrum(const std::vector<double>& e, double period, const std::string& name, const std::string& label) {
  plot::Series l;
  l.label = label;
  l.colour = plot::series_colour(name);
  const double n = static_cast<double>(e.size());
  if (e.size() < 8) return l;
  const double f0 = 1.0 / (n * period), f1 = 0.5 / period;
  for (int i = 0; i < 120; ++i) {
    const double f = f0 * std::pow(f1 / f0, i / 119.0);
    double re = 0.0, im = 0.0;
    for (std::size_t k = 0; k < e.size(); ++k) {
      const double phase = 2.0 * std::numbers::pi * f * period * static_cast<double>(k);
      re += e[k] * std::cos(phase);
      im -= e[k] * std::sin(phase);
    }
    l.x.push_back(f);
    l.y.push_back(std::sqrt(re * re + im * im) * 2.0 / n);
  }
  return l;
}

// Only the level channels are plotted: the report is about the levels the calibration fitted.
bool plotted(const Series& s) { return s.channel == "y_dwe_mm" || s.channel == "y_dw_mm"; }

// The correlation matrix as coloured cells: blue −1, white 0, red +1, grey undetermined.
std::string correlation_picture(const Calibration& c) {
  const std::size_t p = c.parameters.size();
  const double cell = 44, left = 170, top = 10;
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << left + cell * p + 20 << "' height='" << top + cell * p + 130
    << "'>";
  for (std::size_t a = 0; a < p; ++a) {
    s << "<text x='" << left - 6 << "' y='" << top + cell * a + cell / 2 + 4 << "' font-size='12' text-anchor='end'>"
      << html::escape(c.parameters[a].name) << "</text>";
    const double x = left + cell * a + cell / 2, y = top + cell * p + 8;
    s << "<text x='" << x << "' y='" << y << "' font-size='12' transform='rotate(60 " << x << ' ' << y << ")'>"
      << html::escape(c.parameters[a].name) << "</text>";
    for (std::size_t b = 0; b < p; ++b) {
      const double r = c.correlation.size() > a && c.correlation[a].size() > b ? c.correlation[a][b] : NAN;
      std::string fill = "#bbbbbb";
      if (std::isfinite(r)) {
        const int fade = static_cast<int>(255.0 * (1.0 - std::min(std::abs(r), 1.0)));
        char buf[16];
        std::snprintf(buf, sizeof buf, r >= 0 ? "#ff%02x%02x" : "#%02x%02xff", fade, fade);
        fill = buf;
      }
      s << "<rect x='" << left + cell * b << "' y='" << top + cell * a << "' width='" << cell << "' height='" << cell
        << "' fill='" << fill << "' stroke='#fff'/>";
      s << "<text x='" << left + cell * b + cell / 2 << "' y='" << top + cell * a + cell / 2 + 4
        << "' font-size='11' text-anchor='middle'>" << (std::isfinite(r) ? format_fixed(r, 2) : "n/a") << "</text>";
    }
  }
  s << "</svg>";
  return s.str();
}

// The model-form choices refitted (model_form.hpp) as a table, the verdict below; empty when none.
std::string model_form_table(const ModelForms& m) {
  if (!m.done) return m.message.empty() ? "" : "<h3>Model form</h3><p>" + html::escape(m.message) + "</p>";
  const bool validated = !std::isnan(m.validation_rms_mm);
  std::ostringstream h;
  h << "<h3>Model form</h3><p>Each choice added to the model and refitted from the estimates; it pays at "
    << "&Delta;BIC &lt; &minus;10 on " << format_fixed(m.effective_samples, 0) << " effective samples"
    << (validated ? ", a validation fit no worse" : "") << " and " << format_fixed(100.0 * kTimeOffsetGain, 0) << " % of the cost removed on twice the cells.</p><table><tr><th>choice</th><th>adds</th>"
    << "<th>cost per sample</th><th>removes</th><th>&Delta;BIC</th>" << (validated ? "<th>validation RMS</th>" : "")
    << "<th>estimates, notes</th></tr><tr><td class='l'>as calibrated</td><td class='l'></td><td>" << format_g(m.cost, 4)
    << "</td><td></td><td></td>" << (validated ? "<td>" + format_g(m.validation_rms_mm, 3) + " mm</td>" : "") << "<td></td></tr>";
  for (const ModelFormTrial& t : m.trials) {
    h << "<tr" << (t.pays ? " style='font-weight:bold'" : "") << "><td class='l'>" << html::escape(t.name) << "</td><td class='l'>"
      << html::escape(t.description) << "</td>";
    if (!t.ok) {
      h << "<td class='l' colspan='" << (validated ? 5 : 4) << "'>failed: " << html::escape(t.message) << "</td></tr>";
      continue;
    }
    h << "<td>" << format_g(t.cost, 4) << "</td><td>" << format_fixed(100.0 * t.removed, 1) << " %</td><td>"
      << format_fixed(t.bic_change, 0) << "</td>";
    if (validated) h << "<td>" << format_g(t.validation_rms_mm, 3) << " mm</td>";
    std::string estimates;
    for (const FormEstimate& e : t.estimates) {
      estimates += (estimates.empty() ? "" : ", ") + e.name + " = " + format_g(e.value, 4) +
                   (std::isfinite(e.std) ? " &plusmn; " + format_g(e.std, 2) : "") + " " + html::escape(e.unit);
    }
    if (!t.note.empty()) estimates += (estimates.empty() ? "" : "; ") + html::escape(t.note);
    h << "<td class='l'>" << estimates << "</td></tr>";
  }
  h << "</table><p>" << html::escape(m.verdict) << "</p>";
  return h.str();
}

// Where the residual lives (residual_breakdown.hpp) as a table; each choice's share shaded green
// by how much it removes (red where its refit fits the group worse), so where a choice acts shows
// at a glance.
std::string breakdown_table(const Calibration& c) {
  const bool shares = c.model_forms.done && !c.model_forms.breakdown.choices.empty();
  const ResidualBreakdown& b = shares ? c.model_forms.breakdown : c.breakdown;
  if (b.groups.empty()) return "";
  std::ostringstream h;
  h << "<h3>Where the residual lives</h3><p>The level residual (recorded &minus; model) by operating point, by each "
    << "recording's own thirds of the level, by time after a command switch and by band (moving averages over 20 s "
    << "and 2 s); a mean comparable to the RMS is a static error."
    << (shares ? " Each choice's column: the share of the group's squared residual its refit removes "
                 "(the reference refitted for the model form)." : "")
    << "</p><table><tr><th>axis</th><th>group</th><th>samples</th><th>RMS</th><th>mean</th>";
  for (const std::string& name : b.choices) h << "<th>" << html::escape(name) << "</th>";
  h << "</tr>";
  std::string axis;
  for (const BreakdownGroup& g : b.groups) {
    h << "<tr><td class='l'>" << (g.axis == axis ? "" : html::escape(g.axis)) << "</td><td class='l'>" << html::escape(g.name)
      << "</td><td>" << g.samples << "</td><td>" << format_fixed(g.rms_mm, 3) << " mm</td><td>" << format_fixed(g.mean_mm, 3)
      << " mm</td>";
    axis = g.axis;
    for (const double share : g.removed) {
      if (!std::isfinite(share)) {
        h << "<td>-</td>";
        continue;
      }
      const double strength = std::min(1.0, std::abs(share));
      const std::string colour = share >= 0.0 ? "40,160,70" : "200,60,50";
      h << "<td style='background:rgba(" << colour << "," << format_fixed(0.6 * strength, 2) << ")'>"
        << format_fixed(100.0 * share, 0) << " %</td>";
    }
    h << "</tr>";
  }
  h << "</table>";
  return h.str();
}

}  // namespace

std::vector<plot::Figure> report_figures(const Calibration& c) {
  std::vector<plot::Figure> figures;
  if (!c.ok) return figures;
  for (const auto& s : c.series) {
    if (!plotted(s) || s.t.empty()) continue;
    const std::string what = s.recording + (s.validation ? " (validation)" : "") + ", " + s.channel;
    const std::string stem = plot::file_stem(s.recording) + (s.validation ? "_validation_" : "_") + plot::file_stem(s.channel);
    plot::Comparison cmp;
    cmp.t = s.t;
    cmp.measured = {"recorded", s.recorded, "recorded"};
    cmp.models = {{"nominal", s.nominal, "nominal scenario"}, {"calibrated", s.calibrated, "calibrated scenario"}};
    cmp.name = stem + "_levels_and_residual";
    cmp.title = what + ": recorded level and scenarios, residual below";
    figures.push_back(plot::measured_vs_model(cmp));
    const std::vector<plot::Curve> residuals = plot::residuals(cmp);
    figures.push_back(plot::autocorrelation_figure(stem + "_residual_autocorrelation", what + ": autocorrelation of the residual",
                                                   residuals));
    cmp.name = stem + "_step_zoom";
    cmp.title = what + ": the response to the largest command change";
    if (auto zoom = plot::step_zoom(cmp, s.u, "mm")) figures.push_back(std::move(*zoom));
    plot::Figure spectra;
    spectra.name = stem + "_residual_spectrum";
    spectra.title = what + ": amplitude spectrum of the residual";
    plot::Panel p;
    p.x = plot::Axis{"f", "Hz"};
    p.x.scale = plot::Scale::log;
    p.y = plot::Axis{"|residual| amplitude", "mm"};
    p.y.scale = plot::Scale::log;
    const double period = s.t.size() > 1 ? s.t[1] - s.t[0] : 1.0;
    for (const auto& r : residuals) p.series.push_back(spectrum(r.y, period, r.name, r.legend()));
    spectra.panels.push_back(std::move(p));
    figures.push_back(std::move(spectra));
  }
  return figures;
}

std::string html_report(const Calibration& c, const std::string& title) {
  std::ostringstream h;
  h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>" << html::escape(title) << "</title><style>"
    << "body{font-family:sans-serif;max-width:1000px;margin:1em auto;color:#222}table{border-collapse:collapse}"
    << "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f3f3f3}"
    << "td.l{text-align:left}pre{background:#f7f7f7;padding:8px}</style></head><body>";
  h << "<h1>" << html::escape(title) << "</h1>";
  if (!c.ok) {
    h << "<p>Calibration failed: " << html::escape(c.message) << "</p></body></html>";
    return h.str();
  }
  h << "<p>Weighted cost per sample " << format_g(c.cost_before, 4) << " &rarr; " << format_g(c.cost_after, 4) << "; "
    << c.simulations << " simulations, " << c.starts << " start(s), " << c.iterations << " iterations, "
    << format_fixed(c.seconds, 1) << " s. Standard deviations include the residual autocorrelation ("
    << format_fixed(c.inflation, 1) << "&times; variance).</p>";
  h << "<h2>Parameters</h2><table><tr><th>parameter</th><th>start</th><th>estimate</th><th>&plusmn; std</th>"
    << "<th>grid-converged</th><th>bounds</th><th>unit</th><th>scenario key</th><th>sensitivity</th></tr>";
  for (const auto& p : c.parameters) {
    h << "<tr><td class='l'>" << html::escape(p.name) << "</td><td>" << format_g(p.start, 5) << "</td><td>" << format_g(p.value, 5)
      << (p.at_bound ? " (bound)" : "") << "</td><td>" << (std::isfinite(p.std) ? format_g(p.std, 2) : "not determined")
      << "</td><td>" << (c.grid.done ? format_g(p.converged, 5) : "-") << "</td><td>[" << format_g(p.low, 4) << ", " << format_g(p.high, 4) << "]</td><td>" << html::escape(p.unit)
      << "</td><td class='l'>" << html::escape(p.key) << "</td><td>" << format_g(p.sensitivity, 3) << "</td></tr>";
  }
  h << "</table>";
  if (c.grid.done) {
    h << "<p>Grid-converged: the estimate extrapolated (Richardson, first order) from its linear response to twice "
      << "the cells to a grid without discretisation error &mdash; for a measured value or a model on another grid. "
      << "The calibrated scenario keeps the estimate, the best for its own grid.</p>";
  }
  if (!c.identifiability.empty()) {
    h << "<h3>Not identifiable from these recordings</h3><ul>";
    for (const auto& u : c.identifiability) {
      std::string names;
      for (const auto& n : u.parameters) names += (names.empty() ? "" : ", ") + n;
      h << "<li><b>" << html::escape(names) << "</b>: " << html::escape(u.reason)
        << (u.determined.empty() ? "" : "; determined: " + html::escape(u.determined)) << "</li>";
    }
    h << "</ul>";
  }
  h << "<h2>Correlation matrix</h2>" << correlation_picture(c);
  h << "<h2>Fit per recording and channel</h2><table><tr><th>recording</th><th>channel</th><th>RMS before</th>"
    << "<th>RMS after</th><th>Nrmse before</th><th>Nrmse after</th></tr>";
  for (const auto& f : c.fits) {
    h << "<tr><td class='l'>" << html::escape(f.recording) << (f.validation ? " (validation)" : "") << "</td><td class='l'>"
      << html::escape(f.channel) << "</td><td>" << format_fixed(f.rms_before, 3) << "</td><td>" << format_fixed(f.rms_after, 3)
      << "</td><td>" << format_fixed(f.nrmse_before, 1) << " %</td><td>" << format_fixed(f.nrmse_after, 1)
      << " %</td></tr>";
  }
  h << "</table>";
  if (c.grid.done) h << "<p><b>Grid check.</b> " << html::escape(c.grid.verdict) << ".</p>";
  if (!c.gate_laws.empty()) h << "<h3>Gate laws</h3><pre>" << html::escape(gate_law_lines(c)) << "</pre>";
  if (!c.grids.empty()) h << "<h3>Grid</h3><pre>" << html::escape(grid_lines(c)) << "</pre>";
  h << model_form_table(c.model_forms);
  h << breakdown_table(c);
  if (!c.time_offset_note.empty()) h << "<h3>Time offset</h3><p>" << html::escape(c.time_offset_note) << "</p>";
  if (!c.written_note.empty()) h << "<h3>Model written</h3><p>" << html::escape(c.written_note) << "</p>";
  h << "<h2 id='responses'>Responses and residuals</h2>";
  for (const auto& figure : report_figures(c)) h << plot::render_svg(figure) << '\n';
  h << "<h2>Solver</h2><pre>" << html::escape(c.solver_report) << "</pre></body></html>";
  return h.str();
}

}  // namespace canalsim::calibration
