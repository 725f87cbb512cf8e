// report.html: the tables, the claims and the figures, self-contained (the figures inline as SVG,
// drawn by plot/; no script, no network).
#include "study/render.hpp"

#include <cmath>
#include <sstream>

#include "core/format.hpp"
#include "core/html.hpp"
#include "plot/composites.hpp"
#include "plot/palette.hpp"
#include "study/text.hpp"

namespace canalsim::study {

using namespace canalsim::reduced;

namespace {

// Every k-th sample so that at most `points` remain (0 = all).
std::vector<double> thin(const std::vector<double>& v, std::size_t points) {
  const std::size_t step = (points == 0 || v.size() <= points) ? 1 : (v.size() + points - 1) / points;
  std::vector<double> out;
  for (std::size_t i = 0; i < v.size(); i += step) out.push_back(v[i]);
  return out;
}

const char* kHtmlHead = R"html(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>canalsim reproduce — the paper's study on the simulated laboratory canal</title>
<style>
body{font-family:system-ui,sans-serif;max-width:1100px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:90%}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
th{background:#f3f3f3} td:first-child{text-align:left}
.holds{color:#17692b}.fails{color:#a3141c}.why{color:#333;font-size:92%}
.plot{margin:.5em 0 1.5em} .plot svg{background:#fff;border:1px solid #ddd;display:block}
small{color:#666}
</style></head><body>
)html";

// Markdown table lines (| a | b |) to an HTML table, other lines to paragraphs/lists/headings.
std::string markdown_to_html(const std::string& md) {
  std::istringstream in(md);
  std::ostringstream out;
  std::string line;
  bool in_table = false, header = false, in_list = false;
  const auto inline_md = [](std::string s) {
    s = html::escape(s);
    for (const std::string mark : {"**", "`"}) {
      bool open = true;
      for (auto p = s.find(mark); p != std::string::npos; p = s.find(mark, p)) {
        const std::string tag = mark == "**" ? (open ? "<b>" : "</b>") : (open ? "<code>" : "</code>");
        s.replace(p, mark.size(), tag);
        open = !open;
      }
    }
    return s;
  };
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '|') {
      if (!in_table) {
        out << "<table>\n";
        in_table = true;
        header = true;
      }
      if (line.rfind("|---", 0) == 0) continue;
      std::vector<std::string> cells;
      std::size_t p = 1;
      while (p < line.size()) {
        const auto q = line.find('|', p);
        if (q == std::string::npos) break;
        auto c = line.substr(p, q - p);
        const auto a = c.find_first_not_of(' '), b = c.find_last_not_of(' ');
        cells.push_back(a == std::string::npos ? "" : c.substr(a, b - a + 1));
        p = q + 1;
      }
      out << "<tr>";
      for (const auto& c : cells) out << (header ? "<th>" : "<td>") << inline_md(c) << (header ? "</th>" : "</td>");
      out << "</tr>\n";
      header = false;
      continue;
    }
    if (in_table) {
      out << "</table>\n";
      in_table = false;
    }
    if (line.rfind("- ", 0) == 0) {
      if (!in_list) out << "<ul>\n";
      in_list = true;
      const bool holds = line.find("**holds**") != std::string::npos;
      // A failing claim's cause (" *Why:* …") in the text's colour: the verdict is red, not the reason.
      std::string claim = line.substr(2), why;
      if (const auto at = claim.find(" *Why:* "); at != std::string::npos) {
        why = claim.substr(at + 8);
        claim.resize(at);
      }
      out << "<li><span class=\"" << (holds ? "holds" : "fails") << "\">" << inline_md(claim) << "</span>";
      if (!why.empty()) out << "<br><span class=\"why\"><i>Why:</i> " << inline_md(why) << "</span>";
      out << "</li>\n";
      continue;
    }
    if (in_list) {
      out << "</ul>\n";
      in_list = false;
    }
    if (line.empty()) continue;
    if (line.rfind("### ", 0) == 0) {
      out << "<h3>" << inline_md(line.substr(4)) << "</h3>\n";
    } else if (line.rfind("## ", 0) == 0) {
      out << "<h2>" << inline_md(line.substr(3)) << "</h2>\n";
    } else if (line.rfind("# ", 0) == 0) {
      out << "<h1>" << inline_md(line.substr(2)) << "</h1>\n";
    } else {
      out << "<p>" << inline_md(line) << "</p>\n";
    }
  }
  if (in_table) out << "</table>\n";
  if (in_list) out << "</ul>\n";
  return out.str();
}

// Recorded and model responses: at each operating point fitted in a table, the models fitted there;
// at each validation point, the nominal models. One panel per model (small multiples).
std::vector<plot::Figure> response_figures(const StudyResult& r, const std::map<std::string, Recording>& recordings,
                                           std::size_t points) {
  std::vector<plot::Figure> figures;
  const auto comparison = [&](const std::string& op) {
    const auto& rec = recordings.at(op);
    plot::Comparison c;
    c.t = thin(rec.column(columns::time), points);
    c.measured = {"recorded", thin(rec.column(columns::level_downstream_end), points), "recorded y_dwe"};
    return c;
  };
  std::vector<std::string> fit_ops;
  for (const auto& t : r.tables) {
    for (const auto& op : t.spec.experiments) {
      if (std::find(fit_ops.begin(), fit_ops.end(), op) == fit_ops.end()) fit_ops.push_back(op);
    }
  }
  for (const auto& op : fit_ops) {
    plot::Comparison c = comparison(op);
    c.name = "responses_" + plot::file_stem(op);
    c.title = "Recorded and fitted responses at " + op + " (" + recordings.at(op).meta("operating_opening_mm", "?") + " mm)";
    for (const auto& t : r.tables) {
      const auto it = std::find(t.spec.experiments.begin(), t.spec.experiments.end(), op);
      if (it == t.spec.experiments.end()) continue;
      const auto k = static_cast<std::size_t>(it - t.spec.experiments.begin());
      c.models.push_back({upper_name(t.spec.kind), thin(t.fits[k].response.front(), points),
                          upper_name(t.spec.kind) + ", Nrmse " + format_fixed(t.fits[k].nrmse.front(), 1) + " %"});
    }
    figures.push_back(plot::small_multiples(c));
  }
  for (const auto* v : {&r.table5, &r.table8}) {
    for (std::size_t row = 0; row < v->experiments.size(); ++row) {
      const auto& op = v->experiments[row];
      plot::Comparison c = comparison(op);
      c.name = "validation_" + plot::file_stem(op);
      c.title = "Validation of the nominal models at " + op + " (paper " + v->paper_experiments[row] + ", " +
                recordings.at(op).meta("operating_opening_mm", "?") + " mm)";
      for (std::size_t m = 0; m < v->models.size(); ++m) {
        c.models.push_back({v->models[m], thin(v->results[row][m].response, points),
                            v->models[m] + " nominal, Nrmse " + format_fixed(v->results[row][m].nrmse, 1) + " %"});
      }
      figures.push_back(plot::small_multiples(c));
    }
  }
  return figures;
}

// Nrmse against γ (Figures 8 and 10): one figure per table swept, the best γ of each curve dotted.
std::vector<plot::Figure> gamma_figures(const StudyResult& r) {
  std::vector<plot::Figure> figures;
  for (const auto& t : r.tables) {
    if (t.sweeps.empty() || !t.nominal_sweep) continue;
    plot::Figure f;
    f.name = "gamma_" + plot::file_stem(upper_name(t.spec.kind));
    f.title = "Nrmse against γ, " + upper_name(t.spec.kind) + " (dots: best γ)";
    f.panel_height = 230.0;
    plot::Panel p;
    p.x = plot::data_range_axis("γ", "", 5);
    p.y = plot::Axis{"Nrmse", "%"};
    double best = INFINITY;
    const auto add = [&](const GammaSweep& sweep, const std::string& name, const std::string& label, std::size_t index) {
      plot::Series s;
      s.label = label + " (best γ " + format_fixed(sweep.gamma[sweep.best], 2) + ")";
      s.colour = plot::series_colour(name, index);
      s.x = sweep.gamma;
      s.y = sweep.nrmse;
      s.marks = {sweep.best};
      best = std::min(best, sweep.nrmse[sweep.best]);
      return s;
    };
    for (std::size_t k = 0; k < t.sweeps.size(); ++k) p.series.push_back(add(t.sweeps[k], t.spec.experiments[k], t.spec.experiments[k], k));
    plot::Series nominal = add(*t.nominal_sweep, "nominal", "nominal", 0);
    nominal.dashed = true;
    p.series.push_back(std::move(nominal));
    // Fits that collapse at low γ would squash the interesting part: 40 points below the best at most.
    double lowest = INFINITY;
    for (const auto& s : p.series) {
      for (const double v : s.y) lowest = std::min(lowest, v);
    }
    if (lowest < best - 40.0) p.y.low = std::floor((best - 40.0) / 10.0) * 10.0;
    f.panels.push_back(std::move(p));
    figures.push_back(std::move(f));
  }
  return figures;
}

// Flow regimes (Figure 6): y_up against the free-flow limit y_lc (eq. 23), and y_dwe.
std::vector<plot::Figure> regime_figures(const StudyResult& r, const std::map<std::string, Recording>& recordings,
                                         std::size_t points) {
  std::vector<plot::Figure> figures;
  for (const auto& reg : r.regimes) {
    const auto& rec = recordings.at(reg.experiment);
    if (!rec.has(columns::upstream_level) || !rec.has(columns::gate_position)) continue;
    const auto& y_dwe = rec.column(columns::level_downstream_end);
    const auto& x_up = rec.column(columns::gate_position);
    std::vector<double> y_lc(rec.size());
    for (std::size_t k = 0; k < rec.size(); ++k) y_lc[k] = free_flow_limit_mm(y_dwe[k], x_up[k]);
    plot::Figure f;
    f.name = "flow_regime_" + plot::file_stem(reg.experiment);
    f.title = "Flow condition at " + reg.experiment + " (" + format_fixed(reg.operating_opening_mm, 0) + " mm): free flow on " +
              format_fixed(100.0 * reg.free_fraction, 1) + " % of the samples";
    f.panel_height = 200.0;
    plot::Panel p;
    p.x = plot::data_range_axis("t", "s");
    p.y = plot::Axis{"level", "mm"};
    const std::vector<double> t = thin(rec.column(columns::time), points);
    const auto add = [&](const std::string& name, const std::string& label, const std::vector<double>& y, std::size_t index) {
      plot::Series s;
      s.label = label;
      s.colour = plot::series_colour(name, index);
      s.x = t;
      s.y = thin(y, points);
      p.series.push_back(std::move(s));
    };
    add("y_up", "y_up", rec.column(columns::upstream_level), 0);
    add("y_lc", "y_lc (eq. 23)", y_lc, 1);
    add("recorded", "y_dwe", y_dwe, 0);
    f.panels.push_back(std::move(p));
    figures.push_back(std::move(f));
  }
  return figures;
}

// The PRBS spectrum (Figure 4): the lines of the recorded command, the envelope, a unit step's
// 1/ω and the half-power level that defines the bandwidth.
plot::Figure spectrum_figure(const StudyResult& r) {
  plot::Figure f;
  f.name = "prbs_spectrum";
  f.title = "Magnitude of the Fourier transform of a unit-amplitude PRBS and of a unit step";
  f.panel_height = 260.0;
  plot::Panel p;
  p.x = plot::data_range_axis("ω", "rad/s");
  p.y = plot::Axis{"|F(ω)|", ""};
  p.y.scale = plot::Scale::log;
  // Three decades below the envelope's peak: the sinc's zeros would stretch the axis to 1e-16.
  double peak = 0.0;
  for (const double v : r.spectrum.envelope) peak = std::max(peak, v);
  if (peak > 0.0) p.y.low = std::pow(10.0, std::floor(std::log10(peak * 1e-3)));
  const auto add = [&](const std::string& label, const std::string& colour, plot::Style style, const std::vector<double>& x,
                       const std::vector<double>& y) {
    plot::Series s;
    s.label = label;
    s.colour = colour;
    s.style = style;
    s.x = x;
    s.y = y;
    p.series.push_back(std::move(s));
    return &p.series.back();
  };
  // The command's lines in the command's colour, the envelope dark over them.
  add("PRBS lines (recorded command)", plot::series_colour("command"), plot::Style::stems, r.spectrum.omega, r.spectrum.magnitude)
      ->width = 0.6;
  add("envelope Tc √(N+1) |sinc|", plot::series_colour("recorded"), plot::Style::line, r.spectrum.omega, r.spectrum.envelope);
  add("unit step 1/ω", plot::series_colour("step", 3), plot::Style::line, r.spectrum.omega, r.spectrum.step);
  if (!r.spectrum.omega.empty()) {
    add("envelope max/√2 (−3 dB)", plot::series_colour("half power", 0), plot::Style::line, {r.spectrum.omega.front(), r.spectrum.omega.back()},
        {peak / std::sqrt(2.0), peak / std::sqrt(2.0)})->dashed = true;
  }
  f.panels.push_back(std::move(p));
  return f;
}

std::string figures_html(const std::vector<plot::Figure>& figures) {
  std::string out;
  for (const auto& f : figures) out += "<div class=\"plot\">" + plot::render_svg(f) + "</div>\n";
  return out;
}

}  // namespace

std::vector<plot::Figure> report_figures(const StudyResult& r, const std::map<std::string, Recording>& recordings,
                                         const StudyOptions& options) {
  std::vector<plot::Figure> figures = response_figures(r, recordings, options.plot_points);
  const auto append = [&](std::vector<plot::Figure> more) {
    for (auto& f : more) figures.push_back(std::move(f));
  };
  append(gamma_figures(r));
  append(regime_figures(r, recordings, options.plot_points));
  figures.push_back(spectrum_figure(r));
  return figures;
}

std::string to_html(const StudyResult& r, const std::map<std::string, Recording>& recordings,
                    const StudyOptions& options, const std::string& extra_section) {
  std::ostringstream html;
  html << kHtmlHead << markdown_to_html(to_markdown(r))
       << "<h2 id=\"responses\">Recorded and model responses</h2>\n" << figures_html(response_figures(r, recordings, options.plot_points))
       << "<h2 id=\"gamma\">Nrmse against γ (Figures 8 and 10)</h2>\n" << figures_html(gamma_figures(r))
       << "<h2 id=\"regimes\">Flow regimes (Figure 6): y_up, y_lc = 0.81 y_dwe (y_dwe/x_up)^0.72, y_dwe</h2>"
          "<p><small>Free flow where y_up &gt; y_lc (condition 8), submerged where y_up &lt; y_lc "
          "(condition 10).</small></p>\n" << figures_html(regime_figures(r, recordings, options.plot_points))
       << "<h2 id=\"spectrum\">PRBS spectrum (Figure 4)</h2><p><small>Design half-power bandwidth "
       << format_fixed(r.spectrum.bandwidth_design_rad_s, 3) << " rad/s, measured " << format_fixed(r.spectrum.bandwidth_measured_rad_s, 3)
       << " rad/s, paper 5.58 rad/s.</small></p>\n" << figures_html({spectrum_figure(r)})
       << extra_section << "</body></html>\n";
  return html.str();
}

}  // namespace canalsim::study
