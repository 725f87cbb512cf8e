// report.html: the tables, the claims and the figures, self-contained (data and plotting code
// inline; no network). The plotting code is study/report.js.
#include "study/render.hpp"

#include <cmath>
#include <sstream>

#include "core/html.hpp"
#include "study/text.hpp"

namespace canalsim::study {

using namespace canalsim::reduced;

extern const char* const kReportScript;  // study/report.js, embedded at configure time

namespace {

// Every k-th sample so that at most `points` remain (0 = all).
std::vector<double> thin(const std::vector<double>& v, std::size_t points, int digits = 3) {
  const std::size_t step = (points == 0 || v.size() <= points) ? 1 : (v.size() + points - 1) / points;
  std::vector<double> out;
  const double scale = std::pow(10.0, digits);
  for (std::size_t i = 0; i < v.size(); i += step) out.push_back(std::round(v[i] * scale) / scale);
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
.plot{margin:.5em 0 1.5em} .plot svg{background:#fff;border:1px solid #ddd}
.legend span{margin-right:1em;font-size:85%}
small{color:#666}
</style></head><body>
)html";

// Plotting code: chart(id, spec) draws line series (x, y arrays) as inline SVG.

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

nlohmann::json series(const std::string& name, const std::vector<double>& x, const std::vector<double>& y,
                      std::size_t points, const std::string& color = "") {
  nlohmann::json s = {{"name", name}, {"x", thin(x, points, 3)}, {"y", thin(y, points, 3)}};
  if (!color.empty()) s["color"] = color;
  return s;
}

}  // namespace

std::string to_html(const StudyResult& r, const std::map<std::string, Recording>& recordings,
                    const StudyOptions& options, const std::string& extra_section) {
  const std::size_t points = options.plot_points;
  nlohmann::json data;
  // Recorded vs model responses: fitted models at op1–op4, nominal models at the validation points.
  data["responses"] = nlohmann::json::array();
  std::vector<std::string> fit_ops;
  for (const auto& t : r.tables) {
    for (const auto& op : t.spec.experiments) {
      if (std::find(fit_ops.begin(), fit_ops.end(), op) == fit_ops.end()) fit_ops.push_back(op);
    }
  }
  for (const auto& op : fit_ops) {
    const auto& rec = recordings.at(op);
    const auto& t_s = rec.column(columns::time);
    nlohmann::json plot;
    plot["title"] = "Recorded and fitted responses at " + op + " (" + rec.meta("operating_opening_mm", "?") +
                    " mm)";
    plot["series"].push_back(series("recorded y_dwe", t_s, rec.column(columns::level_downstream_end), points, "#222"));
    for (const auto& t : r.tables) {
      const auto it = std::find(t.spec.experiments.begin(), t.spec.experiments.end(), op);
      if (it == t.spec.experiments.end()) continue;
      const auto k = static_cast<std::size_t>(it - t.spec.experiments.begin());
      plot["series"].push_back(series(upper_name(t.spec.kind) + " (Nrmse " + format_fixed(t.fits[k].nrmse.front(), 1) + " %)",
                                      t_s, t.fits[k].response.front(), points));
    }
    data["responses"].push_back(plot);
  }
  for (const auto* v : {&r.table5, &r.table8}) {
    for (std::size_t row = 0; row < v->experiments.size(); ++row) {
      const auto& op = v->experiments[row];
      const auto& rec = recordings.at(op);
      const auto& t_s = rec.column(columns::time);
      nlohmann::json plot;
      plot["title"] = "Validation of the nominal models at " + op + " (paper " + v->paper_experiments[row] + ", " +
                      rec.meta("operating_opening_mm", "?") + " mm)";
      plot["series"].push_back(series("recorded y_dwe", t_s, rec.column(columns::level_downstream_end), points, "#222"));
      for (std::size_t m = 0; m < v->models.size(); ++m) {
        plot["series"].push_back(series(v->models[m] + " nominal (Nrmse " + format_fixed(v->results[row][m].nrmse, 1) + " %)",
                                        t_s, v->results[row][m].response, points));
      }
      data["responses"].push_back(plot);
    }
  }
  // Nrmse against γ (Figures 8 and 10).
  data["gamma"] = nlohmann::json::array();
  for (const auto& t : r.tables) {
    if (t.sweeps.empty()) continue;
    nlohmann::json g;
    g["title"] = "Nrmse against γ, " + upper_name(t.spec.kind) + " (dots: best γ)";
    double ymin = 1e300;
    for (std::size_t k = 0; k < t.sweeps.size(); ++k) {
      auto s = series(t.spec.experiments[k] + " (best γ " + format_fixed(t.sweeps[k].gamma[t.sweeps[k].best], 2) + ")",
                      t.sweeps[k].gamma, t.sweeps[k].nrmse, 0);
      s["mark"] = t.sweeps[k].best;
      g["series"].push_back(s);
      ymin = std::min(ymin, t.sweeps[k].nrmse[t.sweeps[k].best]);
    }
    auto s = series("nominal (best γ " + format_fixed(t.nominal_sweep->gamma[t.nominal_sweep->best], 2) + ")",
                    t.nominal_sweep->gamma, t.nominal_sweep->nrmse, 0);
    s["mark"] = t.nominal_sweep->best;
    s["dash"] = "5 3";
    g["series"].push_back(s);
    g["ymin"] = ymin - 40.0;  // keep the interesting part visible when low γ fits collapse
    data["gamma"].push_back(g);
  }
  // Flow regimes (Figure 6).
  data["regimes"] = nlohmann::json::array();
  for (const auto& reg : r.regimes) {
    const auto& rec = recordings.at(reg.experiment);
    if (!rec.has(columns::upstream_level) || !rec.has(columns::gate_position)) continue;
    const auto& t_s = rec.column(columns::time);
    const auto& y_dwe = rec.column(columns::level_downstream_end);
    const auto& x_up = rec.column(columns::gate_position);
    std::vector<double> y_lc(rec.size());
    for (std::size_t k = 0; k < rec.size(); ++k) y_lc[k] = free_flow_limit_mm(y_dwe[k], x_up[k]);
    nlohmann::json f;
    f["title"] = "Flow condition at " + reg.experiment + " (" + format_fixed(reg.operating_opening_mm, 0) +
                 " mm): free flow on " + format_fixed(100.0 * reg.free_fraction, 1) + " % of the samples";
    f["series"].push_back(series("y_up", t_s, rec.column(columns::upstream_level), points, "#1f77b4"));
    f["series"].push_back(series("y_lc (eq. 23)", t_s, y_lc, points, "#d62728"));
    f["series"].push_back(series("y_dwe", t_s, y_dwe, points, "#222"));
    data["regimes"].push_back(f);
  }
  double peak = 0.0;
  for (double v : r.spectrum.envelope) peak = std::max(peak, v);
  data["spectrum"] = {{"omega", thin(r.spectrum.omega, 0, 4)},
                      {"magnitude", thin(r.spectrum.magnitude, 0, 4)},
                      {"envelope", thin(r.spectrum.envelope, 0, 4)},
                      {"step", thin(r.spectrum.step, 0, 4)},
                      {"peak", peak}};

  std::ostringstream html;
  html << kHtmlHead << markdown_to_html(to_markdown(r))
       << "<h2>Recorded and model responses</h2><div id=\"responses\"></div>\n"
       << "<h2>Nrmse against γ (Figures 8 and 10)</h2><div id=\"gamma\"></div>\n"
       << "<h2>Flow regimes (Figure 6): y_up, y_lc = 0.81 y_dwe (y_dwe/x_up)^0.72, y_dwe</h2>"
          "<p><small>Free flow where y_up &gt; y_lc (condition 8), submerged where y_up &lt; y_lc "
          "(condition 10).</small></p><div id=\"regimes\"></div>\n"
       << "<h2>PRBS spectrum (Figure 4)</h2><p><small>Design half-power bandwidth "
       << format_fixed(r.spectrum.bandwidth_design_rad_s, 3) << " rad/s, measured " << format_fixed(r.spectrum.bandwidth_measured_rad_s, 3)
       << " rad/s, paper 5.58 rad/s.</small></p><div id=\"spectrum\"></div>\n"
       << extra_section << "<script>\nconst DATA = ";
  std::string json = data.dump();
  // Keep "</script>" out of the inline data.
  for (std::size_t p = json.find("</"); p != std::string::npos; p = json.find("</", p + 2)) json.replace(p, 2, "<\\/");
  html << json << ";\n" << kReportScript << "</script>\n</body></html>\n";
  return html.str();
}

}  // namespace canalsim::study
