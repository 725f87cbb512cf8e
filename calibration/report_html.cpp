// The HTML report of a calibration: one self-contained page (inline SVG and CSS, no scripts or
// external resources), so it opens offline and can be mailed.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "calibration/report.hpp"

#include "core/html.hpp"
#include "core/format.hpp"

namespace canalsim::calibration {
namespace {


struct Line {
  std::vector<double> x, y;
  std::string colour, label;
};

// A line plot in an SVG of 720 × 240 with axes, ticks at the ends and a legend; log axes when asked.
std::string plot(const std::vector<Line>& lines, const std::string& x_label, const std::string& y_label,
                 bool log_x = false, bool log_y = false) {
  const double W = 720, H = 240, L = 60, R = 150, T = 10, B = 40;
  auto tx = [&](double v) { return log_x ? std::log10(std::max(v, 1e-300)) : v; };
  auto ty = [&](double v) { return log_y ? std::log10(std::max(v, 1e-300)) : v; };
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& l : lines) {
    for (std::size_t k = 0; k < l.x.size(); ++k) {
      if (!std::isfinite(l.y[k]) || (log_x && l.x[k] <= 0) || (log_y && l.y[k] <= 0)) continue;
      x0 = std::min(x0, tx(l.x[k]));
      x1 = std::max(x1, tx(l.x[k]));
      y0 = std::min(y0, ty(l.y[k]));
      y1 = std::max(y1, ty(l.y[k]));
    }
  }
  if (!(x1 > x0)) x1 = x0 + 1;
  if (!(y1 > y0)) { y0 -= 0.5; y1 += 0.5; }
  auto px = [&](double v) { return L + (tx(v) - x0) / (x1 - x0) * (W - L - R); };
  auto py = [&](double v) { return H - B - (ty(v) - y0) / (y1 - y0) * (H - T - B); };
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H << "' class='plot'>";
  s << "<rect x='" << L << "' y='" << T << "' width='" << W - L - R << "' height='" << H - T - B
    << "' fill='none' stroke='#999'/>";
  auto label = [&](double v, bool log) { return format_g(log ? std::pow(10.0, v) : v, 4); };
  s << "<text x='" << L << "' y='" << H - B + 14 << "' font-size='11'>" << label(x0, log_x) << "</text>";
  s << "<text x='" << W - R << "' y='" << H - B + 14 << "' font-size='11' text-anchor='end'>" << label(x1, log_x) << "</text>";
  s << "<text x='" << L - 4 << "' y='" << H - B << "' font-size='11' text-anchor='end'>" << label(y0, log_y) << "</text>";
  s << "<text x='" << L - 4 << "' y='" << T + 10 << "' font-size='11' text-anchor='end'>" << label(y1, log_y) << "</text>";
  s << "<text x='" << (L + W - R) / 2 << "' y='" << H - 6 << "' font-size='12' text-anchor='middle'>" << html::escape(x_label) << "</text>";
  s << "<text x='12' y='" << (H - B + T) / 2 << "' font-size='12' transform='rotate(-90 12 " << (H - B + T) / 2
    << ")' text-anchor='middle'>" << html::escape(y_label) << "</text>";
  int row = 0;
  for (const auto& l : lines) {
    s << "<polyline fill='none' stroke='" << l.colour << "' stroke-width='1' points='";
    // At most ~1500 points per line keeps the page light.
    const std::size_t stride = std::max<std::size_t>(1, l.x.size() / 1500);
    for (std::size_t k = 0; k < l.x.size(); k += stride) {
      if (!std::isfinite(l.y[k]) || (log_x && l.x[k] <= 0) || (log_y && l.y[k] <= 0)) continue;
      s << format_fixed(px(l.x[k]), 1) << ',' << format_fixed(py(l.y[k]), 1) << ' ';
    }
    s << "'/>";
    s << "<line x1='" << W - R + 10 << "' x2='" << W - R + 30 << "' y1='" << T + 12 + 16 * row << "' y2='"
      << T + 12 + 16 * row << "' stroke='" << l.colour << "' stroke-width='2'/>";
    s << "<text x='" << W - R + 34 << "' y='" << T + 16 + 16 * row << "' font-size='11'>" << html::escape(l.label) << "</text>";
    ++row;
  }
  s << "</svg>";
  return s.str();
}

// Amplitude spectrum |DFT| of a residual at 120 log-spaced frequencies between 1/T and the
// Nyquist frequency (direct sums: a few hundred thousand operations per series).
Line spectrum(const std::vector<double>& e, double period, const std::string& colour, const std::string& label) {
  Line l{{}, {}, colour, label};
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

}  // namespace

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
  if (!c.time_offset_note.empty()) h << "<h3>Time offset</h3><p>" << html::escape(c.time_offset_note) << "</p>";
  if (!c.written_note.empty()) h << "<h3>Model written</h3><p>" << html::escape(c.written_note) << "</p>";
  h << "<h2>Responses and residuals</h2>";
  for (const auto& s : c.series) {
    if (s.channel != "y_dwe_mm" && s.channel != "y_dw_mm") continue;
    h << "<h3>" << html::escape(s.recording) << (s.validation ? " (validation)" : "") << " &mdash; " << html::escape(s.channel) << "</h3>";
    h << plot({{s.t, s.recorded, "#777", "recorded"}, {s.t, s.nominal, "#d62728", "nominal"},
               {s.t, s.calibrated, "#1f77b4", "calibrated"}},
              "t [s]", s.channel);
    std::vector<double> before(s.t.size()), after(s.t.size());
    for (std::size_t k = 0; k < s.t.size(); ++k) {
      before[k] = s.recorded[k] - s.nominal[k];
      after[k] = s.recorded[k] - s.calibrated[k];
    }
    h << plot({{s.t, before, "#d62728", "residual before"}, {s.t, after, "#1f77b4", "residual after"}}, "t [s]",
              "recorded - model");
    const double period = s.t.size() > 1 ? s.t[1] - s.t[0] : 1.0;
    h << plot({spectrum(before, period, "#d62728", "before"), spectrum(after, period, "#1f77b4", "after")}, "f [Hz]",
              "|residual| amplitude", true, true);
  }
  h << "<h2>Solver</h2><pre>" << html::escape(c.solver_report) << "</pre></body></html>";
  return h.str();
}

}  // namespace canalsim::calibration
