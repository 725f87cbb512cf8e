#include "plot/composites.hpp"

#include <algorithm>
#include <cmath>

#include "core/statistics.hpp"
#include "plot/palette.hpp"

namespace canalsim::plot {
namespace {

Series line(const std::string& name, const std::string& label, const std::vector<double>& x, const std::vector<double>& y,
            std::size_t index = 0) {
  Series s;
  s.label = label;
  s.colour = series_colour(name, index);
  s.x = x;
  s.y = y;
  return s;
}

Axis time_axis() { return data_range_axis("t", "s"); }

// A figure of `c` whose panels share the time axis.
Figure shared_time_figure(const Comparison& c) {
  Figure f;
  f.name = c.name;
  f.title = c.title;
  f.share_x = true;
  return f;
}

// The panel of the quantity itself (levels), in its unit.
Panel quantity_panel(const Comparison& c) {
  Panel level;
  level.x = time_axis();
  level.y = Axis{c.quantity, c.unit};
  return level;
}

Axis residual_axis(const Comparison& c) {
  Axis a{"residual", c.unit};
  a.symmetric = true;
  a.min_half_span = c.residual_floor;
  a.ticks = 4;
  return a;
}

std::vector<double> slice(const std::vector<double>& v, std::size_t from, std::size_t to) {
  return {v.begin() + static_cast<std::ptrdiff_t>(std::min(from, v.size())),
          v.begin() + static_cast<std::ptrdiff_t>(std::min(to, v.size()))};
}

}  // namespace

std::vector<Curve> residuals(const Comparison& c) {
  std::vector<Curve> out;
  for (const auto& m : c.models) {
    Curve r{m.name, std::vector<double>(c.measured.y.size(), NAN), "residual, " + m.legend()};
    for (std::size_t k = 0; k < r.y.size() && k < m.y.size(); ++k) r.y[k] = c.measured.y[k] - m.y[k];
    out.push_back(std::move(r));
  }
  return out;
}

Figure measured_vs_model(const Comparison& c) {
  Figure f = shared_time_figure(c);
  Panel level = quantity_panel(c);
  level.markers = c.markers;
  level.series.push_back(line(c.measured.name, c.measured.legend(), c.t, c.measured.y));
  for (std::size_t i = 0; i < c.models.size(); ++i) {
    level.series.push_back(line(c.models[i].name, c.models[i].legend(), c.t, c.models[i].y, i));
  }
  Panel residual;
  residual.x = time_axis();
  residual.y = residual_axis(c);
  residual.height = 130.0;
  residual.windows = c.windows;
  residual.window_label = c.window_label;
  residual.markers = c.markers;
  const std::vector<Curve> r = residuals(c);
  for (std::size_t i = 0; i < r.size(); ++i) residual.series.push_back(line(r[i].name, "", c.t, r[i].y, i));
  f.panels = {std::move(level), std::move(residual)};
  return f;
}

Figure small_multiples(const Comparison& c, int columns) {
  Figure f;
  f.name = c.name;
  f.title = c.title;
  f.columns = columns;
  f.share_x = true;
  f.panel_height = 170.0;
  // One y range for every panel: the eye compares panels only on common axes.
  std::vector<double> all = c.measured.y;
  for (const auto& m : c.models) all.insert(all.end(), m.y.begin(), m.y.end());
  const ResolvedAxis common = resolve_axis(Axis{c.quantity, c.unit}, all);
  for (std::size_t i = 0; i < c.models.size(); ++i) {
    Panel p;
    p.title = c.models[i].legend();
    p.x = time_axis();
    p.y = Axis{c.quantity, c.unit};
    p.y.low = common.low;
    p.y.high = common.high;
    p.markers = c.markers;
    p.series.push_back(line(c.measured.name, c.measured.legend(), c.t, c.measured.y));
    p.series.push_back(line(c.models[i].name, c.models[i].name, c.t, c.models[i].y, i));
    f.panels.push_back(std::move(p));
  }
  return f;
}

Autocorrelation residual_autocorrelation(const std::vector<double>& residual, int max_lag, double z) {
  Autocorrelation a;
  std::vector<double> finite;
  for (const double v : residual) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  a.samples = finite.size();
  const int lags = std::min<int>(max_lag, static_cast<int>(finite.size()) - 1);
  const std::vector<double> r = autocorrelation(finite, std::max(lags, 0));
  for (int k = 1; k <= lags; ++k) {
    a.lags.push_back(k);
    a.values.push_back(r[static_cast<std::size_t>(k)]);
  }
  a.bound = a.samples > 0 ? z / std::sqrt(static_cast<double>(a.samples)) : 0.0;
  return a;
}

Figure autocorrelation_figure(const std::string& name, const std::string& title, const std::vector<Curve>& residuals,
                              int max_lag) {
  Figure f;
  f.name = name;
  f.title = title;
  f.columns = static_cast<int>(std::clamp<std::size_t>(residuals.size(), 1, 2));
  f.panel_height = 150.0;
  std::vector<Autocorrelation> all;
  double largest = 0.0;
  for (const auto& r : residuals) {
    all.push_back(residual_autocorrelation(r.y, max_lag));
    largest = std::max(largest, all.back().bound * 1.5);
    for (const double v : all.back().values) largest = std::max(largest, std::abs(v));
  }
  for (std::size_t i = 0; i < residuals.size(); ++i) {
    const Autocorrelation& a = all[i];
    Panel p;
    p.title = residuals[i].legend() + " (n = " + std::to_string(a.samples) + ")";
    p.x = Axis{"lag", "samples"};
    p.x.low = 0.0;
    p.x.high = std::max(1.0, static_cast<double>(a.lags.size()));
    p.y = Axis{"r(k)", ""};
    p.y.symmetric = true;
    p.y.min_half_span = std::min(1.0, largest);
    p.y.ticks = 4;
    Series band;
    band.label = "95 % band ±1.96/√n";
    band.colour = kBandShade;
    band.style = Style::band;
    band.x = {0.0, p.x.high};
    band.y = {-a.bound, -a.bound};
    band.y_upper = {a.bound, a.bound};
    p.series.push_back(std::move(band));
    Series stems = line(residuals[i].name, "", a.lags, a.values, i);
    stems.style = Style::stems;
    stems.width = 2.0;
    p.series.push_back(std::move(stems));
    f.panels.push_back(std::move(p));
  }
  return f;
}

std::optional<double> largest_command_change(const std::vector<double>& t, const std::vector<double>& u) {
  std::optional<double> at;
  double largest = 0.0;
  for (std::size_t k = 1; k < u.size() && k < t.size(); ++k) {
    const double change = std::abs(u[k] - u[k - 1]);
    if (std::isfinite(change) && change > largest) {
      largest = change;
      at = t[k];
    }
  }
  return at;
}

std::optional<Figure> step_zoom(const Comparison& c, const std::vector<double>& command, const std::string& command_unit) {
  const std::optional<double> change = largest_command_change(c.t, command);
  if (!change || c.t.size() < 4) return std::nullopt;
  // A window of a twelfth of the recording, at least 20 samples: long enough for the level to
  // answer the step, short enough to see its delay and rise.
  const double dt = (c.t.back() - c.t.front()) / static_cast<double>(c.t.size() - 1);
  const double span = std::max((c.t.back() - c.t.front()) / 12.0, 20.0 * dt);
  const double from_t = *change - 0.2 * span, to_t = *change + 0.8 * span;
  const auto from = static_cast<std::size_t>(std::lower_bound(c.t.begin(), c.t.end(), from_t) - c.t.begin());
  const auto to = static_cast<std::size_t>(std::upper_bound(c.t.begin(), c.t.end(), to_t) - c.t.begin());
  Figure f = shared_time_figure(c);
  Panel level = quantity_panel(c);
  level.markers = {{*change, "command change"}};
  const std::vector<double> t = slice(c.t, from, to);
  level.series.push_back(line(c.measured.name, c.measured.legend(), t, slice(c.measured.y, from, to)));
  for (std::size_t i = 0; i < c.models.size(); ++i) {
    level.series.push_back(line(c.models[i].name, c.models[i].legend(), t, slice(c.models[i].y, from, to), i));
  }
  Panel u;
  u.x = time_axis();
  u.y = Axis{"command", command_unit};
  u.y.ticks = 3;
  u.height = 90.0;
  u.markers = {{*change, ""}};
  Series step = line("command", "command", t, slice(command, from, to));
  step.style = Style::step;
  u.series.push_back(std::move(step));
  f.panels = {std::move(level), std::move(u)};
  return f;
}

Figure bode_figure(const std::string& name, const std::string& title, const std::vector<double>& omega,
                   const std::vector<FrequencyCurve>& curves, const std::optional<Window>& band) {
  Figure f;
  f.name = name;
  f.title = title;
  f.share_x = true;
  Axis w{"ω", "rad/s"};
  w.scale = Scale::log;
  Panel gain, phase;
  gain.x = phase.x = w;
  gain.y = Axis{"gain", "dB"};
  phase.y = Axis{"phase", "deg"};
  gain.height = 200.0;
  phase.height = 170.0;
  if (band) {
    gain.markers = {{band->start, "band"}, {band->end, ""}};
    phase.markers = {{band->start, ""}, {band->end, ""}};
  }
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const std::string label = curves[i].label.empty() ? curves[i].name : curves[i].label;
    gain.series.push_back(line(curves[i].name, label, omega, curves[i].gain_db, i));
    phase.series.push_back(line(curves[i].name, "", omega, curves[i].phase_deg, i));
  }
  f.panels = {std::move(gain), std::move(phase)};
  return f;
}

}  // namespace canalsim::plot
