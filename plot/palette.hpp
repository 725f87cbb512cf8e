// One fixed palette for every figure: a series that means the same thing (the recorded level, the
// nominal model, the LFOM, …) has the same colour in every report and file, so a reader who has
// learnt the colours once reads every plot at a glance.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace canalsim::plot {

// The colour of a named series, matched without regard to case on the whole name: recorded
// (measured), nominal, calibrated, corrected, pde (the linearised pool), the reduced models liom,
// lfom, nliom-s, nliom-f, nlfom-s, nlfom-f, id, idz, the command and the upstream level y_up. ""
// for a name the palette does not know.
std::string named_colour(std::string_view name);

// The colour of a name the palette knows, else the index'th of the palette's other colours
// (cycled), which no named series uses.
std::string series_colour(std::string_view name, std::size_t index = 0);

// Shades that are not series: a shaded window, the confidence band, a grid line.
inline constexpr const char* kWindowShade = "#fdd9b5";
inline constexpr const char* kBandShade = "#c6dbef";
inline constexpr const char* kGridColour = "#e4e4e4";
inline constexpr const char* kMinorGridColour = "#f2f2f2";

}  // namespace canalsim::plot
