#include "sweep/plot.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/format.hpp"
#include "core/html.hpp"

namespace canalsim::sweep {
namespace {

constexpr double kWidth = 360, kHeight = 240, kLeft = 58, kRight = 12, kTop = 26, kBottom = 42;

struct Axis {
  double low = 0.0, high = 1.0;  // in plotted coordinates (log10 of the value on a log axis)
  bool log = false;
  std::vector<double> ticks;     // values, not coordinates
  double coordinate(double value) const { return log ? std::log10(value) : value; }
};

// Ticks of 1, 2 or 5 times a power of ten, three to seven of them across [low, high].
std::vector<double> linear_ticks(double low, double high) {
  const double raw = (high - low) / 4.0;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * power;
  for (const double m : {1.0, 2.0, 5.0}) {
    if (m * power >= raw) {
      step = m * power;
      break;
    }
  }
  std::vector<double> ticks;
  for (double k = std::ceil(low / step); k * step <= high * (1.0 + 1e-12) + 1e-300; k += 1.0) {
    ticks.push_back(std::abs(k) < 0.5 ? 0.0 : k * step);  // an exact 0, never 1e-17
  }
  return ticks;
}

// 1, 2 and 5 times each power of ten inside [10^low, 10^high]; the decades alone when those are
// more than seven.
std::vector<double> log_ticks(double low, double high) {
  std::vector<double> all, decades;
  for (double e = std::floor(low); e <= std::ceil(high); e += 1.0) {
    for (const double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, e);
      const double c = std::log10(v);
      if (c < low - 1e-12 || c > high + 1e-12) continue;
      all.push_back(v);
      if (m == 1.0) decades.push_back(v);
    }
  }
  return all.size() > 7 && decades.size() >= 2 ? decades : all;
}

// The axis over the finite values (positive ones on a log axis), padded by 5 % each side.
Axis axis_over(const std::vector<double>& values, bool log) {
  Axis a;
  a.log = log;
  double low = INFINITY, high = -INFINITY;
  for (const double v : values) {
    if (!std::isfinite(v) || (log && v <= 0.0)) continue;
    low = std::min(low, a.coordinate(v));
    high = std::max(high, a.coordinate(v));
  }
  if (!(low <= high)) low = 0.0, high = 1.0;
  if (high == low) {
    const double half = log ? 0.5 : (low == 0.0 ? 1.0 : 0.1 * std::abs(low));
    low -= half;
    high += half;
  }
  const double pad = 0.05 * (high - low);
  a.low = low - pad;
  a.high = high + pad;
  a.ticks = log ? log_ticks(a.low, a.high) : linear_ticks(a.low, a.high);
  return a;
}

}  // namespace

std::string scatter_svg(const std::vector<ScatterSeries>& series, const std::string& x_label,
                        const std::string& y_label, bool log_x) {
  std::vector<double> xs, ys;
  for (const auto& s : series) {
    xs.insert(xs.end(), s.x.begin(), s.x.end());
    ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  const Axis x = axis_over(xs, log_x), y = axis_over(ys, false);
  const auto px = [&](double v) { return kLeft + (x.coordinate(v) - x.low) / (x.high - x.low) * (kWidth - kLeft - kRight); };
  const auto py = [&](double v) { return kHeight - kBottom - (v - y.low) / (y.high - y.low) * (kHeight - kTop - kBottom); };
  const auto at = [](double v) { return format_fixed(v, 1); };
  std::ostringstream s;
  s << "<svg xmlns='http://www.w3.org/2000/svg' width='" << kWidth << "' height='" << kHeight << "' class='plot'>"
    << "<rect x='" << kLeft << "' y='" << kTop << "' width='" << kWidth - kLeft - kRight << "' height='"
    << kHeight - kTop - kBottom << "' fill='none' stroke='#999'/>";
  for (const double t : x.ticks) {
    s << "<line x1='" << at(px(t)) << "' x2='" << at(px(t)) << "' y1='" << kTop << "' y2='" << kHeight - kBottom
      << "' stroke='#eee'/><text x='" << at(px(t)) << "' y='" << kHeight - kBottom + 14
      << "' font-size='10' text-anchor='middle'>" << format_g(t, 4) << "</text>";
  }
  for (const double t : y.ticks) {
    s << "<line x1='" << kLeft << "' x2='" << kWidth - kRight << "' y1='" << at(py(t)) << "' y2='" << at(py(t))
      << "' stroke='#eee'/><text x='" << kLeft - 4 << "' y='" << at(py(t) + 3) << "' font-size='10' text-anchor='end'>"
      << format_g(t, 4) << "</text>";
  }
  s << "<text x='" << (kLeft + kWidth - kRight) / 2 << "' y='" << kHeight - 6 << "' font-size='11' text-anchor='middle'>"
    << html::escape(x_label) << "</text><text x='12' y='" << (kTop + kHeight - kBottom) / 2
    << "' font-size='11' text-anchor='middle' transform='rotate(-90 12 " << (kTop + kHeight - kBottom) / 2 << ")'>"
    << html::escape(y_label) << "</text>";
  double legend_x = kLeft;
  for (const auto& one : series) {
    for (std::size_t k = 0; k < one.x.size() && k < one.y.size(); ++k) {
      const double a = one.x[k], b = one.y[k];
      if (!std::isfinite(a) || !std::isfinite(b) || (log_x && a <= 0.0)) continue;
      s << "<circle cx='" << at(px(a)) << "' cy='" << at(py(b)) << "' r='3' fill='" << one.colour
        << "' fill-opacity='0.7'/>";
    }
    s << "<circle cx='" << legend_x + 4 << "' cy='12' r='4' fill='" << one.colour << "'/><text x='" << legend_x + 12
      << "' y='16' font-size='11'>" << html::escape(one.label) << "</text>";
    legend_x += 24.0 + 6.5 * static_cast<double>(one.label.size());
  }
  s << "</svg>";
  return s.str();
}

}  // namespace canalsim::sweep
