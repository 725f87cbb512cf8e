// A small scatter plot as inline SVG, for the sweep's report: figures of every case against one
// varied key.
#pragma once

#include <string>
#include <vector>

namespace canalsim::sweep {

struct ScatterSeries {
  std::string label;   // the legend's
  std::string colour;  // an SVG colour, "#1f77b4"
  std::vector<double> x, y;  // points whose coordinates are not finite are left out
};

// A 360 × 240 scatter with both axes ticked at round numbers (1, 2 or 5 times a power of ten;
// decades on a logarithmic x axis), the axes' labels (with their units) and a legend.
std::string scatter_svg(const std::vector<ScatterSeries>& series, const std::string& x_label,
                        const std::string& y_label, bool log_x = false);

}  // namespace canalsim::sweep
