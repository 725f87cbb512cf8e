// An SVG figure: one or more panels in a grid, each with real axes (nice ticks, grid lines, labels
// with units, linear or logarithmic), its series drawn as lines, steps, points, stems or shaded
// bands, shaded x windows and marked instants, and one legend for the whole figure. Every report's
// plots and every standalone .svg file are built with it.
#pragma once

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/files.hpp"

namespace canalsim::plot {

enum class Scale { linear, log };

struct Axis {
  std::string label;  // "level", "ω"
  std::string unit;   // "mm", "rad/s"; shown as "label [unit]"
  Scale scale = Scale::linear;
  // Fixed limits; NaN: from the data.
  double low = std::numeric_limits<double>::quiet_NaN();
  double high = std::numeric_limits<double>::quiet_NaN();
  // A range centred on zero (a residual): [-m, m] with m the largest |value|, at least min_half_span.
  bool symmetric = false;
  // The smallest half-width of the range: data that hardly vary (a flat residual) get a calm range
  // of this half-width around their centre rather than their noise blown up to the panel's height.
  double min_half_span = 0.0;
  // The range is widened to the first ticks outside the data (levels, gains); a time axis keeps
  // the data's own range (false).
  bool extend_to_ticks = true;
  int ticks = 5;  // about this many intervals
  std::string title() const { return unit.empty() ? label : label + " [" + unit + "]"; }
};

// An axis over the data's own range (a time or a sweep), with about `ticks` intervals.
inline Axis data_range_axis(const std::string& label, const std::string& unit, int ticks = 8) {
  Axis a{label, unit};
  a.extend_to_ticks = false;
  a.ticks = ticks;
  return a;
}

enum class Style { line, step, scatter, stems, band };

struct Series {
  std::string label;   // in the legend; "" keeps it out
  std::string colour;  // an SVG colour (plot/palette.hpp)
  Style style = Style::line;
  std::vector<double> x, y;
  std::vector<double> y_upper;  // a band's upper edge (y is its lower edge)
  bool dashed = false;
  double width = 1.3;
  // Points of a line marked with a dot (a sweep's best γ, say): indices into x.
  std::vector<std::size_t> marks;
};

struct Window {  // an x range shaded behind the series
  double start = 0.0, end = 0.0;
};

struct Marker {  // a vertical dashed line at x with a short label beside it
  double x = 0.0;
  std::string label;
};

struct Panel {
  std::string title;
  Axis x, y;
  std::vector<Series> series;
  std::vector<Window> windows;
  std::string window_label;  // the windows' legend entry; "" keeps it out
  std::vector<Marker> markers;
  double height = 0.0;  // the plot area's height in px; 0: the figure's panel_height
};

struct Figure {
  std::string name;   // file stem of the standalone file and prefix of the SVG's ids: [A-Za-z0-9_-]
  std::string title;
  std::vector<Panel> panels;
  int columns = 1;
  double width = 960.0;         // the whole figure, px
  double panel_height = 200.0;  // a plot area's default height, px
  // Panels in one column share x: tick labels and the x title only under the bottom one.
  bool share_x = false;
  std::size_t max_points = 1500;  // per line; longer series are reduced to their min/max per bucket
};

// Where a panel's plot area sits and how data map to its pixels.
struct ResolvedAxis {
  double low = 0.0, high = 1.0;  // data values at the ends
  Scale scale = Scale::linear;
  std::vector<double> ticks, minor_ticks;
  double step = 1.0;  // a linear axis' tick step
  double fraction(double value) const;  // 0 at low, 1 at high
};

struct PanelFrame {
  double left = 0.0, top = 0.0, width = 0.0, height = 0.0;  // the plot area, px
  double y_title_x = 0.0;  // where the y axis title is centred: the same in every panel of a column
  ResolvedAxis x, y;
  double pixel_x(double value) const { return left + x.fraction(value) * width; }
  double pixel_y(double value) const { return top + height - y.fraction(value) * height; }
};

// The axis range and ticks of `axis` over the finite values (positive ones on a log axis).
ResolvedAxis resolve_axis(const Axis& axis, const std::vector<double>& values);

// Every panel's frame, in the order of figure.panels.
std::vector<PanelFrame> layout(const Figure& figure);
// The figure's total height, px.
double figure_height(const Figure& figure);

// The figure as an <svg> element (inline in an HTML page; ids prefixed by the figure's name).
std::string render_svg(const Figure& figure);
// The figure as a standalone .svg file (XML declaration, white background).
std::string svg_document(const Figure& figure);

// A file stem made of `text`: letters, digits, '-' and '_' kept, anything else '_' ("op1*" → "op1_").
std::string file_stem(const std::string& text);

// The figures as standalone files DIR/NAME.svg, for a command's all-or-nothing output set
// (core/files.hpp); a name used twice gets "_2", "_3".
std::vector<FileContents> svg_files(const std::filesystem::path& dir, const std::vector<Figure>& figures);

}  // namespace canalsim::plot
