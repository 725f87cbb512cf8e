// Where an axis puts its ticks and what they read: steps of 1, 2 or 5 times a power of ten on a
// linear axis, decades (with minor ticks at 2…9) on a logarithmic one, and labels that read as a
// person writes them — "0" for zero, never "-0.00", as many decimals as the step needs.
#pragma once

#include <string>
#include <vector>

namespace canalsim::plot {

// The smallest of 1, 2 or 5 times a power of ten that is at least `raw` (> 0).
double nice_step(double raw);

// The tick step for [low, high] with at most about `target` intervals: nice_step of the span over
// `target`. A range of zero width gets the step of its magnitude (1 for a range at 0).
double tick_step(double low, double high, int target = 5);

// The multiples of `step` inside [low, high] (a relative tolerance of 1e-9 at the ends), each
// computed as an integer times the step so that 3 × 0.1 reads 0.3 and the middle one is an exact 0.
std::vector<double> ticks_at(double low, double high, double step);

// ticks_at(low, high, tick_step(low, high, target)): [0, 0.37] → 0, 0.1, 0.2, 0.3.
std::vector<double> nice_ticks(double low, double high, int target = 5);

// A tick's label: zero is "0"; fixed decimals enough for `step` (0.25 → 2) for steps from 1e-4
// to 1e6, else %g with the digits the step needs ("5e-10"). Through core/format.hpp.
std::string tick_label(double value, double step);

// The powers of ten inside [low, high] (values, both > 0).
std::vector<double> log_decades(double low, double high);
// 2, 3, …, 9 times each power of ten inside [low, high].
std::vector<double> log_minor_ticks(double low, double high);
// A decade's label: "0.01", "0.1", "1", "10", "1000" from 1e-3 to 1e4, else "1e-05", "1e+06".
std::string log_tick_label(double value);

}  // namespace canalsim::plot
