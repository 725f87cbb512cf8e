// The figures that system-identification users know, built on plot/figure.hpp: the measured level
// against the models with the residual below it, the residual's autocorrelation with its 95 %
// confidence band, a zoom on the response to one command change, small multiples (one panel per
// model instead of all of them in one tangle) and the Bode plot (gain in dB and phase against log ω).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "plot/figure.hpp"

namespace canalsim::plot {

// A named series: `name` picks its colour (plot/palette.hpp: "recorded", "nominal", "LFOM", …),
// `label` is its legend entry ("" reads `name`).
struct Curve {
  std::string name;
  std::vector<double> y;
  std::string label;
  std::string legend() const { return label.empty() ? name : label; }
};

// A recorded level and the models' predictions of it over one time base.
struct Comparison {
  std::string name, title;  // the figure's file stem and heading
  std::vector<double> t;    // [s]
  Curve measured;
  std::vector<Curve> models;
  std::string quantity = "level", unit = "mm";
  std::vector<Window> windows;  // shaded in the residual panel
  std::string window_label;
  std::vector<Marker> markers;  // on both panels (the start of the held-out part, say)
  // A residual smaller than this [mm] is drawn on ±this: a clean fit looks calm, not like noise.
  double residual_floor = 0.5;
};

// The residual measured − model of every model, in the comparison's unit.
std::vector<Curve> residuals(const Comparison& c);

// Two panels sharing t: the level (measured and models) and below it the residuals [mm] on a
// range symmetric about zero.
Figure measured_vs_model(const Comparison& c);

// One panel per model, each the measured level and that model, all on the same axes.
Figure small_multiples(const Comparison& c, int columns = 2);

// The sample autocorrelation r(k) of a residual at lags 1…max_lag and its 95 % confidence band
// ±z/√n for white noise of n samples (z = 1.96).
struct Autocorrelation {
  std::vector<double> lags, values;
  double bound = 0.0;
  std::size_t samples = 0;
};
Autocorrelation residual_autocorrelation(const std::vector<double>& residual, int max_lag, double z = 1.96);

// One panel per residual (small multiples on one r axis): r(k) as stems and the band shaded.
Figure autocorrelation_figure(const std::string& name, const std::string& title, const std::vector<Curve>& residuals,
                              int max_lag = 50);

// The instant of the largest change of a sampled command, or nothing when it never changes.
std::optional<double> largest_command_change(const std::vector<double>& t, const std::vector<double>& command);

// A short window around the largest change of `command` (a fifth of it before the change): the
// level and models above, the command as a step below. Nothing when the command never changes.
std::optional<Figure> step_zoom(const Comparison& c, const std::vector<double>& command, const std::string& command_unit);

// A frequency response: gain [dB] and unwrapped phase [deg] at the figure's ω.
struct FrequencyCurve {
  std::string name;
  std::vector<double> gain_db, phase_deg;
  std::string label;
};

// Gain in dB above phase in degrees, against ω on a log axis with decades; `band` marks [low, high]
// when given (the PRBS band).
Figure bode_figure(const std::string& name, const std::string& title, const std::vector<double>& omega,
                   const std::vector<FrequencyCurve>& curves, const std::optional<Window>& band = std::nullopt);

}  // namespace canalsim::plot
