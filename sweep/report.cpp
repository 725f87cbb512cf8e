#include "sweep/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/format.hpp"
#include "core/html.hpp"
#include "plot/figure.hpp"
#include "plot/palette.hpp"
#include "sweep/cases.hpp"
#include "sweep/compute.hpp"
#include "sweep/table.hpp"

namespace canalsim::sweep {
namespace {

constexpr std::size_t kFailuresListed = 50;

// The table's rows as cells, with their columns found by name.
struct ParsedTable {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;

  // The column's numbers, NaN where a cell is empty (not defined, or a failed case); empty when
  // the table has no such column.
  std::vector<double> numbers(const std::string& column) const {
    const auto at = std::find(columns.begin(), columns.end(), column);
    if (at == columns.end()) return {};
    const auto c = static_cast<std::size_t>(at - columns.begin());
    std::vector<double> out;
    for (const auto& row : rows) out.push_back(row[c].empty() ? std::nan("") : std::strtod(row[c].c_str(), nullptr));
    return out;
  }
  std::vector<std::string> texts(const std::string& column) const {
    const auto c = static_cast<std::size_t>(std::find(columns.begin(), columns.end(), column) - columns.begin());
    std::vector<std::string> out;
    for (const auto& row : rows) out.push_back(row[c]);
    return out;
  }
};

std::string values_text(const Variation& v) {
  if (const auto& d = v.distribution) {
    switch (d->kind) {
      case DistributionKind::uniform: return "uniform on [" + format_g(d->first) + ", " + format_g(d->second) + ")";
      case DistributionKind::normal: return "normal, mean " + format_g(d->first) + ", std " + format_g(d->second);
      case DistributionKind::lognormal: return "lognormal, median " + format_g(d->first) + ", sigma " + format_g(d->second);
    }
  }
  if (v.grid.size() <= 8) {
    std::string text;
    for (const double x : v.grid) {
      if (!text.empty()) text += ", ";
      text += format_g(x);
    }
    return text;
  }
  return std::to_string(v.grid.size()) + " values from " + format_g(v.grid.front()) + " to " + format_g(v.grid.back()) +
         (v.logarithmic ? ", log-spaced" : "");
}

std::string what_was_swept(const SweepFile& sweep, std::size_t cases) {
  std::ostringstream s;
  std::string experiments;
  for (const auto& e : sweep.experiments) experiments += (experiments.empty() ? "" : ", ") + e;
  s << "<p>Base scenario <code>" << html::escape(sweep.scenario) << "</code>, experiments " << html::escape(experiments)
    << (sweep.duration_s ? " (each " + format_g(*sweep.duration_s) + " s long)" : std::string()) << ": " << cases
    << " cases, " << grid_point_count(sweep) << " grid point(s)";
  if (sweep.seed) s << " × " << sweep.draws << " draw(s) (seed " << *sweep.seed << ")";
  s << " × " << sweep.experiments.size() << " experiment(s).</p>\n<table><tr><th>key</th><th>values</th></tr>\n";
  for (const auto& v : sweep.vary) {
    s << "<tr><td><code>" << html::escape(v.key) << "</code></td><td>" << html::escape(values_text(v)) << "</td></tr>\n";
  }
  s << "</table>\n";
  std::vector<std::string> computed;
  if (sweep.compute.summary) computed.push_back("the recording's summary");
  for (const auto kind : sweep.compute.fit) computed.push_back(model_column_prefix(kind) + " fitted to the recording");
  if (sweep.compute.linearize) computed.push_back("the linearised pool");
  if (sweep.compute.diagnose) computed.push_back("the diagnosis against the base scenario");
  std::string list;
  for (const auto& c : computed) list += (list.empty() ? "" : "; ") + c;
  s << "<p>Computed for each case: " << html::escape(list) << " (columns in table.csv, docs/sweep.md).</p>\n";
  return s.str();
}

std::string outcome(const ParsedTable& table) {
  const auto status = table.texts("status");
  const auto messages = table.texts("message");
  const auto cases = table.texts("case");
  const auto experiments = table.texts("experiment");
  const auto failed = static_cast<std::size_t>(std::count(status.begin(), status.end(), "failed"));
  std::ostringstream s;
  s << "<h2>Cases</h2>\n<p>" << status.size() - failed << " ok, " << failed << " failed.</p>\n";
  if (failed == 0) return s.str();
  s << "<table><tr><th>case</th><th>experiment</th><th>error</th></tr>\n";
  std::size_t listed = 0;
  for (std::size_t i = 0; i < status.size() && listed < kFailuresListed; ++i) {
    if (status[i] != "failed") continue;
    s << "<tr><td>" << cases[i] << "</td><td>" << html::escape(experiments[i]) << "</td><td>" << html::escape(messages[i])
      << "</td></tr>\n";
    ++listed;
  }
  s << "</table>\n";
  if (failed > listed) s << "<p>… and " << failed - listed << " more (table.csv has every one).</p>\n";
  return s.str();
}

// One scatter per swept key: the fitted LFOM's λ and the linearised pool's band λ of every case.
std::string lambda_plots(const SweepFile& sweep, const ParsedTable& table) {
  const std::string fitted = "LFOM_lambda", linearised = "lin_lambda";
  std::ostringstream s;
  s << "<h2>Fractional order λ against each swept key</h2>\n";
  const auto lfom = table.numbers(fitted), band = table.numbers(linearised);
  if (lfom.empty() && band.empty()) {
    s << "<p>No λ was computed: add \"LFOM\" to compute.fit or set compute.linearize = true.</p>\n";
    return s.str();
  }
  s << "<p>The LFOM fitted to each case's recording (column " << fitted << ") and to the linearised pool's response over the "
       "PRBS band (column " << linearised << "). λ = 1 is a first-order lag; below 1, fractional.</p>\n<div class='plots'>\n";
  // Small multiples: one panel per swept key, all on the same λ axis.
  plot::Figure figure;
  figure.name = "sweep_lambda";
  figure.columns = static_cast<int>(std::clamp<std::size_t>(sweep.vary.size(), 1, 3));
  figure.panel_height = 190.0;
  for (const auto& v : sweep.vary) {
    plot::Panel p;
    p.x = plot::Axis{v.key, ""};
    p.x.scale = v.logarithmic ? plot::Scale::log : plot::Scale::linear;
    p.y = plot::Axis{"λ", ""};
    const std::vector<double> x = table.numbers(v.key);
    const auto add = [&](const std::string& name, const std::string& label, const std::vector<double>& y) {
      plot::Series series;
      series.label = label;
      series.colour = plot::series_colour(name);
      series.style = plot::Style::scatter;
      series.x = x;
      series.y = y;
      p.series.push_back(std::move(series));
    };
    if (!lfom.empty()) add("LFOM", "LFOM fitted to the recording", lfom);
    if (!band.empty()) add("PDE", "LFOM fitted to the linearised pool", band);
    figure.panels.push_back(std::move(p));
  }
  s << plot::render_svg(figure) << "\n";
  s << "</div>\n";
  return s.str();
}

}  // namespace

std::string report_html(const SweepFile& sweep, const std::vector<std::string>& rows) {
  ParsedTable table;
  table.columns = table_columns(sweep);
  for (const auto& row : rows) table.rows.push_back(split_csv_line(row));
  std::ostringstream s;
  s << "<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>canalsim sweep: " << html::escape(sweep.source)
    << "</title>\n<style>body{font-family:sans-serif;max-width:1150px;margin:1em auto;padding:0 1em}"
       "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}"
       ".plots{display:flex;flex-wrap:wrap;gap:12px}</style></head><body>\n"
    << "<h1>Sweep " << html::escape(sweep.source) << "</h1>\n"
    << what_was_swept(sweep, rows.size()) << outcome(table) << lambda_plots(sweep, table) << "</body></html>\n";
  return s.str();
}

}  // namespace canalsim::sweep
