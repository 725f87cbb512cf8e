#include "plot/figure.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/format.hpp"
#include "core/html.hpp"
#include "plot/palette.hpp"
#include "plot/ticks.hpp"

namespace canalsim::plot {
namespace {

// The figure's furniture, in px. Characters are measured at 0.6 em, which holds for the digits and
// lower-case letters of a sans-serif face at these sizes.
constexpr double kTickFont = 11.0, kTitleFont = 13.0, kLabelFont = 12.0;
constexpr double kCharWidth = 0.6 * kTickFont;
constexpr double kSide = 10.0, kRightMargin = 16.0, kPanelTitle = 20.0, kPanelGap = 16.0;
constexpr double kXLabels = 38.0;  // tick labels and the x title under a plot area
constexpr double kLegendRow = 18.0, kSwatch = 24.0;

double text_width(const std::string& s, double font) {
  std::size_t characters = 0;
  for (const unsigned char c : s) characters += (c & 0xC0) != 0x80 ? 1 : 0;  // UTF-8: count characters
  return 0.6 * font * static_cast<double>(characters);
}

// A pixel coordinate in an attribute: one decimal, clamped far outside the figure (a point far off
// a clipped axis), never "-0.0".
std::string at(double v) {
  if (!std::isfinite(v)) v = 0.0;
  v = std::clamp(v, -1e5, 1e5);
  std::string s = format_fixed(v, 1);
  return s == "-0.0" ? "0.0" : s;
}

bool usable(const ResolvedAxis& a, double v) { return std::isfinite(v) && (a.scale == Scale::linear || v > 0.0); }

void collect(std::vector<double>& into, const std::vector<double>& values) { into.insert(into.end(), values.begin(), values.end()); }

std::vector<double> x_values(const Panel& p) {
  std::vector<double> v;
  for (const auto& s : p.series) collect(v, s.x);
  return v;
}

std::vector<double> y_values(const Panel& p) {
  std::vector<double> v;
  for (const auto& s : p.series) {
    collect(v, s.y);
    collect(v, s.y_upper);
  }
  return v;
}

struct Entry {
  std::string label, colour;
  Style style;
  bool dashed, window;
};

std::vector<Entry> legend_entries(const Figure& f) {
  std::vector<Entry> out;
  const auto add = [&](const Entry& e) {
    for (const auto& o : out) {
      if (o.label == e.label && o.colour == e.colour) return;
    }
    out.push_back(e);
  };
  for (const auto& p : f.panels) {
    for (const auto& s : p.series) {
      if (!s.label.empty()) add({s.label, s.colour, s.style, s.dashed, false});
    }
    if (!p.window_label.empty() && !p.windows.empty()) add({p.window_label, kWindowShade, Style::band, false, true});
  }
  return out;
}

double entry_width(const Entry& e) { return kSwatch + 6.0 + text_width(e.label, kTickFont) + 18.0; }

int legend_rows(const Figure& f) {
  const auto entries = legend_entries(f);
  if (entries.empty()) return 0;
  int rows = 1;
  double x = kSide;
  for (const auto& e : entries) {
    if (x + entry_width(e) > f.width - kSide && x > kSide) {
      ++rows;
      x = kSide;
    }
    x += entry_width(e);
  }
  return rows;
}

double header_height(const Figure& f) {
  return (f.title.empty() ? 6.0 : 26.0) + kLegendRow * legend_rows(f) + (legend_rows(f) ? 4.0 : 0.0);
}

bool any_panel_title(const Figure& f) {
  return std::any_of(f.panels.begin(), f.panels.end(), [](const Panel& p) { return !p.title.empty(); });
}

std::size_t rows_of(const Figure& f) {
  const auto c = static_cast<std::size_t>(std::max(f.columns, 1));
  return (f.panels.size() + c - 1) / c;
}

bool shows_x_labels(const Figure& f, std::size_t index) {
  const auto c = static_cast<std::size_t>(std::max(f.columns, 1));
  return !f.share_x || index + c >= f.panels.size();
}

double area_height(const Figure& f, const Panel& p) { return p.height > 0.0 ? p.height : f.panel_height; }

std::vector<ResolvedAxis> resolved_x(const Figure& f) {
  std::vector<ResolvedAxis> out;
  std::vector<double> all;
  if (f.share_x) {
    for (const auto& p : f.panels) collect(all, x_values(p));
  }
  for (const auto& p : f.panels) out.push_back(resolve_axis(p.x, f.share_x ? all : x_values(p)));
  return out;
}

std::string tick_text(const ResolvedAxis& a, double v) {
  return a.scale == Scale::log ? log_tick_label(v) : tick_label(v, a.step);
}

// The log axis' labelled ticks: its decades — every second or third when there are more than eight,
// so that labels never touch — and 2 and 5 times them when it spans less than two.
std::vector<double> labelled_ticks(const ResolvedAxis& a) {
  if (a.scale == Scale::linear) return a.ticks;
  if (a.ticks.size() > 8) {
    const auto every = static_cast<long>((a.ticks.size() + 7) / 8);
    std::vector<double> out;
    for (const double v : a.ticks) {
      if (std::lround(std::log10(v)) % every == 0) out.push_back(v);
    }
    return out;
  }
  if (a.ticks.size() >= 2) return a.ticks;
  std::vector<double> out = a.ticks;
  for (const double v : a.minor_ticks) {
    const double m = v / std::pow(10.0, std::floor(std::log10(v) + 1e-9));
    if (std::abs(m - 2.0) < 1e-6 || std::abs(m - 5.0) < 1e-6) out.push_back(v);
  }
  std::sort(out.begin(), out.end());
  return out;
}

double left_margin(const Figure& f, const std::vector<PanelFrame>& frames) {
  double widest = 0.0;
  for (const auto& fr : frames) {
    for (const double v : labelled_ticks(fr.y)) widest = std::max(widest, text_width(tick_text(fr.y, v), kTickFont));
  }
  const bool titled = std::any_of(f.panels.begin(), f.panels.end(), [](const Panel& p) { return !p.y.title().empty(); });
  return widest + 10.0 + (titled ? kLabelFont + 10.0 : 0.0);
}

// Lines longer than max_points keep each bucket's lowest and highest point in their order, so that
// a spike or a step survives the reduction.
std::vector<std::size_t> kept_points(const Series& s, std::size_t max_points) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  std::vector<std::size_t> out;
  if (n <= max_points || max_points < 4 || s.style != Style::line) {
    for (std::size_t k = 0; k < n; ++k) out.push_back(k);
    return out;
  }
  const std::size_t bucket = (n + max_points / 2 - 1) / (max_points / 2);
  for (std::size_t b = 0; b < n; b += bucket) {
    std::size_t lo = b, hi = b;
    for (std::size_t k = b; k < std::min(n, b + bucket); ++k) {
      if (!std::isfinite(s.y[k])) {
        lo = hi = k;  // a gap stays a gap
        break;
      }
      if (s.y[k] < s.y[lo]) lo = k;
      if (s.y[k] > s.y[hi]) hi = k;
    }
    out.push_back(std::min(lo, hi));
    if (hi != lo) out.push_back(std::max(lo, hi));
  }
  return out;
}

std::string dash(const Series& s) { return s.dashed ? " stroke-dasharray='6 4'" : ""; }

void draw_path(std::ostream& o, const Series& s, const PanelFrame& fr, std::size_t max_points) {
  std::ostringstream d;
  bool open = false;
  double previous_y = NAN;
  for (const std::size_t k : kept_points(s, max_points)) {
    if (!usable(fr.x, s.x[k]) || !usable(fr.y, s.y[k])) {
      open = false;
      continue;
    }
    const double px = fr.pixel_x(s.x[k]), py = fr.pixel_y(s.y[k]);
    if (s.style == Style::step && open) d << 'L' << at(px) << ' ' << at(previous_y);
    d << (open ? 'L' : 'M') << at(px) << ' ' << at(py);
    previous_y = py;
    open = true;
  }
  if (d.tellp() > 0) {
    o << "<path d='" << d.str() << "' fill='none' stroke='" << s.colour << "' stroke-width='" << format_fixed(s.width, 1)
      << "' stroke-linejoin='round'" << dash(s) << "/>";
  }
}

void draw_series(std::ostream& o, const Series& s, const PanelFrame& fr, std::size_t max_points) {
  const std::size_t n = std::min(s.x.size(), s.y.size());
  switch (s.style) {
    case Style::line:
    case Style::step:
      draw_path(o, s, fr, max_points);
      break;
    case Style::scatter:
      for (std::size_t k = 0; k < n; ++k) {
        if (!usable(fr.x, s.x[k]) || !usable(fr.y, s.y[k])) continue;
        o << "<circle cx='" << at(fr.pixel_x(s.x[k])) << "' cy='" << at(fr.pixel_y(s.y[k])) << "' r='3' fill='" << s.colour
          << "' fill-opacity='0.75'/>";
      }
      break;
    case Style::stems: {
      const double base = fr.y.scale == Scale::log ? fr.y.low : std::clamp(0.0, fr.y.low, fr.y.high);
      for (std::size_t k = 0; k < n; ++k) {
        if (!usable(fr.x, s.x[k]) || !usable(fr.y, s.y[k])) continue;
        o << "<line x1='" << at(fr.pixel_x(s.x[k])) << "' x2='" << at(fr.pixel_x(s.x[k])) << "' y1='" << at(fr.pixel_y(base))
          << "' y2='" << at(fr.pixel_y(s.y[k])) << "' stroke='" << s.colour << "' stroke-width='" << format_fixed(s.width, 1) << "'/>";
      }
      break;
    }
    case Style::band: {
      std::ostringstream points;
      const std::size_t m = std::min(n, s.y_upper.size());
      for (std::size_t k = 0; k < m; ++k) {
        if (usable(fr.x, s.x[k]) && usable(fr.y, s.y_upper[k])) points << at(fr.pixel_x(s.x[k])) << ',' << at(fr.pixel_y(s.y_upper[k])) << ' ';
      }
      for (std::size_t k = m; k-- > 0;) {
        if (usable(fr.x, s.x[k]) && usable(fr.y, s.y[k])) points << at(fr.pixel_x(s.x[k])) << ',' << at(fr.pixel_y(s.y[k])) << ' ';
      }
      o << "<polygon points='" << points.str() << "' fill='" << s.colour << "' fill-opacity='0.55' stroke='none'/>";
      break;
    }
  }
  for (const std::size_t k : s.marks) {
    if (k < n && usable(fr.x, s.x[k]) && usable(fr.y, s.y[k])) {
      o << "<circle cx='" << at(fr.pixel_x(s.x[k])) << "' cy='" << at(fr.pixel_y(s.y[k])) << "' r='4' fill='" << s.colour << "'/>";
    }
  }
}

void draw_grid(std::ostream& o, const PanelFrame& fr) {
  const double right = fr.left + fr.width, bottom = fr.top + fr.height;
  for (const double v : fr.x.minor_ticks) {
    o << "<line x1='" << at(fr.pixel_x(v)) << "' x2='" << at(fr.pixel_x(v)) << "' y1='" << at(fr.top) << "' y2='" << at(bottom)
      << "' stroke='" << kMinorGridColour << "'/>";
  }
  for (const double v : fr.y.minor_ticks) {
    o << "<line x1='" << at(fr.left) << "' x2='" << at(right) << "' y1='" << at(fr.pixel_y(v)) << "' y2='" << at(fr.pixel_y(v))
      << "' stroke='" << kMinorGridColour << "'/>";
  }
  for (const double v : fr.x.ticks) {
    o << "<line x1='" << at(fr.pixel_x(v)) << "' x2='" << at(fr.pixel_x(v)) << "' y1='" << at(fr.top) << "' y2='" << at(bottom)
      << "' stroke='" << kGridColour << "'/>";
  }
  for (const double v : fr.y.ticks) {
    // The zero of a linear axis is the line a residual or a gain in dB is read against: darker.
    const bool zero = fr.y.scale == Scale::linear && v == 0.0;
    o << "<line x1='" << at(fr.left) << "' x2='" << at(right) << "' y1='" << at(fr.pixel_y(v)) << "' y2='" << at(fr.pixel_y(v))
      << "' stroke='" << (zero ? "#9a9a9a" : kGridColour) << "'/>";
  }
}

void draw_axes_text(std::ostream& o, const Panel& p, const PanelFrame& fr, bool x_labels) {
  const double bottom = fr.top + fr.height;
  if (x_labels) {
    for (const double v : labelled_ticks(fr.x)) {
      o << "<text x='" << at(fr.pixel_x(v)) << "' y='" << at(bottom + 14) << "' font-size='" << kTickFont
        << "' text-anchor='middle'>" << html::escape(tick_text(fr.x, v)) << "</text>";
    }
    if (!p.x.title().empty()) {
      o << "<text x='" << at(fr.left + fr.width / 2) << "' y='" << at(bottom + 32) << "' font-size='" << kLabelFont
        << "' text-anchor='middle'>" << html::escape(p.x.title()) << "</text>";
    }
  }
  for (const double v : labelled_ticks(fr.y)) {
    o << "<text x='" << at(fr.left - 5) << "' y='" << at(fr.pixel_y(v) + 4) << "' font-size='" << kTickFont
      << "' text-anchor='end'>" << html::escape(tick_text(fr.y, v)) << "</text>";
  }
  if (!p.y.title().empty()) {
    const double cx = fr.y_title_x;
    const double cy = fr.top + fr.height / 2;
    o << "<text x='" << at(cx) << "' y='" << at(cy) << "' font-size='" << kLabelFont << "' text-anchor='middle' transform='rotate(-90 "
      << at(cx) << ' ' << at(cy) << ")'>" << html::escape(p.y.title()) << "</text>";
  }
  if (!p.title.empty()) {
    o << "<text x='" << at(fr.left) << "' y='" << at(fr.top - 6) << "' font-size='" << kLabelFont << "' font-weight='bold'>"
      << html::escape(p.title) << "</text>";
  }
}

void draw_panel(std::ostream& o, const Figure& f, std::size_t index, const PanelFrame& fr) {
  const Panel& p = f.panels[index];
  const std::string clip = file_stem(f.name) + "-clip" + std::to_string(index);
  o << "<clipPath id='" << clip << "'><rect x='" << at(fr.left) << "' y='" << at(fr.top) << "' width='" << at(fr.width)
    << "' height='" << at(fr.height) << "'/></clipPath>";
  o << "<g clip-path='url(#" << clip << ")'>";
  for (const auto& w : p.windows) {
    const double a = fr.pixel_x(w.start), b = fr.pixel_x(w.end);
    o << "<rect x='" << at(std::min(a, b)) << "' y='" << at(fr.top) << "' width='" << at(std::max(1.5, std::abs(b - a)))
      << "' height='" << at(fr.height) << "' fill='" << kWindowShade << "' fill-opacity='0.7'/>";
  }
  draw_grid(o, fr);
  for (const auto& s : p.series) {
    if (s.style == Style::band) draw_series(o, s, fr, f.max_points);  // bands behind the lines
  }
  for (const auto& s : p.series) {
    if (s.style != Style::band) draw_series(o, s, fr, f.max_points);
  }
  o << "</g>";
  for (const auto& m : p.markers) {
    if (!usable(fr.x, m.x) || fr.x.fraction(m.x) < 0.0 || fr.x.fraction(m.x) > 1.0) continue;
    const double x = fr.pixel_x(m.x);
    o << "<line x1='" << at(x) << "' x2='" << at(x) << "' y1='" << at(fr.top) << "' y2='" << at(fr.top + fr.height)
      << "' stroke='#555' stroke-dasharray='4 3'/>";
    if (!m.label.empty()) {
      // The label sits inside the area, on the side with room.
      const bool room_right = fr.x.fraction(m.x) < 0.8;
      o << "<text x='" << at(x + (room_right ? 4 : -4)) << "' y='" << at(fr.top + 13) << "' font-size='" << kTickFont
        << "' fill='#444' stroke='#ffffff' stroke-width='3' paint-order='stroke' text-anchor='" << (room_right ? "start" : "end")
        << "'>" << html::escape(m.label) << "</text>";
    }
  }
  o << "<rect x='" << at(fr.left) << "' y='" << at(fr.top) << "' width='" << at(fr.width) << "' height='" << at(fr.height)
    << "' fill='none' stroke='#666'/>";
  draw_axes_text(o, p, fr, shows_x_labels(f, index));
}

void draw_legend(std::ostream& o, const Figure& f) {
  double x = kSide, y = (f.title.empty() ? 6.0 : 26.0) + 12.0;
  for (const auto& e : legend_entries(f)) {
    if (x + entry_width(e) > f.width - kSide && x > kSide) {
      x = kSide;
      y += kLegendRow;
    }
    if (e.window || e.style == Style::band) {
      o << "<rect x='" << at(x) << "' y='" << at(y - 6) << "' width='" << kSwatch << "' height='10' fill='" << e.colour
        << "' fill-opacity='" << (e.window ? "0.7" : "0.55") << "'/>";
    } else if (e.style == Style::scatter) {
      o << "<circle cx='" << at(x + kSwatch / 2) << "' cy='" << at(y - 1) << "' r='4' fill='" << e.colour << "'/>";
    } else {
      o << "<line x1='" << at(x) << "' x2='" << at(x + kSwatch) << "' y1='" << at(y - 1) << "' y2='" << at(y - 1) << "' stroke='"
        << e.colour << "' stroke-width='2.5'" << (e.dashed ? " stroke-dasharray='6 4'" : "") << "/>";
    }
    o << "<text x='" << at(x + kSwatch + 6) << "' y='" << at(y + 3) << "' font-size='" << kTickFont << "'>" << html::escape(e.label)
      << "</text>";
    x += entry_width(e);
  }
}

}  // namespace

double ResolvedAxis::fraction(double value) const {
  if (scale == Scale::log) return (std::log10(value) - std::log10(low)) / (std::log10(high) - std::log10(low));
  return (value - low) / (high - low);
}

ResolvedAxis resolve_axis(const Axis& axis, const std::vector<double>& values) {
  ResolvedAxis r;
  r.scale = axis.scale;
  double low = INFINITY, high = -INFINITY;
  for (const double v : values) {
    if (!std::isfinite(v) || (axis.scale == Scale::log && v <= 0.0)) continue;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  if (std::isfinite(axis.low)) low = axis.low;
  if (std::isfinite(axis.high)) high = axis.high;
  if (!(low <= high)) {  // no data: a unit range
    low = axis.scale == Scale::log ? 1.0 : 0.0;
    high = axis.scale == Scale::log ? 10.0 : 1.0;
  }
  if (axis.scale == Scale::log) {
    if (high <= low) {
      low /= 2.0;
      high *= 2.0;
    }
    if (axis.extend_to_ticks) {
      if (!std::isfinite(axis.low)) low = std::pow(10.0, std::floor(std::log10(low) + 1e-9));
      if (!std::isfinite(axis.high)) high = std::pow(10.0, std::ceil(std::log10(high) - 1e-9));
    }
    r.low = low;
    r.high = high;
    r.ticks = log_decades(low, high);
    r.minor_ticks = log_minor_ticks(low, high);
    return r;
  }
  if (axis.symmetric) {
    const double m = std::max({std::abs(low), std::abs(high), axis.min_half_span});
    low = -m;
    high = m;
  } else if (high - low < 2.0 * axis.min_half_span) {
    const double centre = 0.5 * (low + high);
    low = centre - axis.min_half_span;
    high = centre + axis.min_half_span;
  }
  if (!(high > low)) {  // a constant: a range of a tenth of its magnitude each side (1 at 0)
    const double half = low == 0.0 ? 1.0 : 0.1 * std::abs(low);
    low -= half;
    high += half;
  }
  r.step = tick_step(low, high, axis.ticks);
  if (axis.extend_to_ticks) {
    if (!std::isfinite(axis.low)) low = std::floor(low / r.step + 1e-9) * r.step;
    if (!std::isfinite(axis.high)) high = std::ceil(high / r.step - 1e-9) * r.step;
  }
  r.low = low;
  r.high = high;
  r.ticks = ticks_at(low, high, r.step);
  return r;
}

std::vector<PanelFrame> layout(const Figure& f) {
  std::vector<PanelFrame> frames(f.panels.size());
  const std::vector<ResolvedAxis> xs = resolved_x(f);
  for (std::size_t i = 0; i < f.panels.size(); ++i) {
    frames[i].x = xs[i];
    frames[i].y = resolve_axis(f.panels[i].y, y_values(f.panels[i]));
  }
  const double left = left_margin(f, frames);
  const auto columns = static_cast<std::size_t>(std::max(f.columns, 1));
  const double cell = (f.width - 2 * kSide) / static_cast<double>(columns);
  const double title = any_panel_title(f) ? kPanelTitle : 6.0;
  double top = header_height(f);
  for (std::size_t row = 0; row < rows_of(f); ++row) {
    double tallest = 0.0, below = kPanelGap;
    for (std::size_t i = row * columns; i < std::min(f.panels.size(), (row + 1) * columns); ++i) {
      tallest = std::max(tallest, area_height(f, f.panels[i]));
      if (shows_x_labels(f, i)) below = kXLabels;
    }
    for (std::size_t i = row * columns; i < std::min(f.panels.size(), (row + 1) * columns); ++i) {
      PanelFrame& fr = frames[i];
      fr.left = kSide + cell * static_cast<double>(i - row * columns) + left;
      fr.y_title_x = fr.left - left + 0.75 * kLabelFont + 2.0;  // the rotated title's glyphs just inside the cell
      fr.width = cell - left - kRightMargin;
      fr.top = top + title;
      fr.height = area_height(f, f.panels[i]);
    }
    top += title + tallest + below;
  }
  return frames;
}

double figure_height(const Figure& f) {
  const std::vector<PanelFrame> frames = layout(f);
  double bottom = header_height(f);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    bottom = std::max(bottom, frames[i].top + frames[i].height + (shows_x_labels(f, i) ? kXLabels : kPanelGap));
  }
  return bottom + 4.0;
}

std::string render_svg(const Figure& f) {
  const std::vector<PanelFrame> frames = layout(f);
  const double height = figure_height(f);
  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg' viewBox='0 0 " << at(f.width) << ' ' << at(height) << "' width='" << at(f.width)
    << "' height='" << at(height) << "' font-family='DejaVu Sans, Arial, sans-serif' style='max-width:100%;height:auto' role='img'>";
  o << "<title>" << html::escape(f.title.empty() ? f.name : f.title) << "</title>";
  o << "<rect width='100%' height='100%' fill='#ffffff'/>";
  if (!f.title.empty()) {
    o << "<text x='" << at(kSide) << "' y='18' font-size='" << kTitleFont << "' font-weight='bold'>" << html::escape(f.title) << "</text>";
  }
  draw_legend(o, f);
  for (std::size_t i = 0; i < f.panels.size(); ++i) draw_panel(o, f, i, frames[i]);
  o << "</svg>";
  return o.str();
}

std::string svg_document(const Figure& f) {
  return "<?xml version='1.0' encoding='UTF-8'?>\n" + render_svg(f) + "\n";
}

std::string file_stem(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const bool kept = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    out += kept ? c : '_';
  }
  return out.empty() ? "figure" : out;
}

std::vector<FileContents> svg_files(const std::filesystem::path& dir, const std::vector<Figure>& figures) {
  std::vector<FileContents> out;
  std::vector<std::string> used;
  for (const auto& f : figures) {
    const std::string stem = file_stem(f.name);
    std::string name = stem;
    for (int n = 2; std::find(used.begin(), used.end(), name) != used.end(); ++n) name = stem + "_" + std::to_string(n);
    used.push_back(name);
    out.emplace_back(dir / (name + ".svg"), svg_document(f));
  }
  return out;
}

}  // namespace canalsim::plot
