// Numbers as people read them, in messages, tables and files: one formatter for the whole project.
#pragma once

#include <string>

namespace canalsim {

// printf's %g with `significant` digits: "0.05", "1e-09", "60.2". The default (6) is also what
// an std::ostream prints; recordings use 10 so that a value survives the round trip to 1e-10.
std::string format_g(double value, int significant = 6);

// Fixed decimals ("%.*f"); non-finite values print as ∞, -∞ or n/a (a NaN), never as inf or nan.
std::string format_fixed(double value, int decimals);

// A figure of a table or report: fixed decimals followed by `unit` ("12.3%"), and "-" alone where
// the quantity is not defined (NaN, or an infinite index): a column of numbers reads "-" for
// "none", not n/a, inf or nan.
std::string format_figure(double value, int decimals, const std::string& unit = "");

// An estimate with its standard deviation, "0.0123 ± 0.0041": the deviation to two significant
// digits and the value to the same decimal place (so a small deviation never prints as ± 0.000).
// A deviation that is zero or not finite was not estimated: "0.0123 (± n/a)"; an infinite value
// (a gate speed without limit) is "∞ (± n/a)".
std::string format_estimate(double value, double std);

// A value echoed in a message: at most the first 60 characters (whole UTF-8 characters) and
// then "... (N characters)", so that a 1 MB field does not make a 1 MB error line.
std::string format_excerpt(const std::string& text);

}  // namespace canalsim
