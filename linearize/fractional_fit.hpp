// The paper's linear fractional-order model (LFOM, eqs. 6–7) fitted directly to a frequency
// response over a band: G_m(iω) = K e^{−iωL} / (T (iω)^λ + 1) (docs/linearization.md §5). The
// fit answers "is the pool fractional in this band?" without a time-domain identification: λ
// near 1 is a first-order lag, well below 1 a fractional one.
#pragma once

#include <complex>
#include <vector>

namespace canalsim::linearize {

struct FractionalFit {
  double gain = 0.0;    // K
  double time = 0.0;    // T [s^λ]
  double order = 1.0;   // λ
  double delay = 0.0;   // L [s]
  double rms_relative_error = 0.0;  // sqrt(mean |G_m − G|² / |G|²) over the band's points
  double integer_rms_relative_error = 0.0;  // the same with λ fixed at 1 (LIOM-like), refitted
  int points = 0;
};

// The PRBS band of the paper's Section 4.3: from the sequence's fundamental 2π/(N T_c)
// (N = 2^stages − 1) to its −3 dB frequency 2π · 0.443 / T_c [rad/s].
struct Band {
  double low = 0.0;
  double high = 0.0;
};
Band prbs_band(int stages, double clock_s);

// Least squares on the relative complex error over the points of (omega, response) inside the
// band (at least 4); K is profiled out exactly, (T, λ, L) by NLopt's Nelder–Mead from the best
// points of a fine scan of L. λ in [0.1, 1.5], L in [0, 2 delay_hint + 2π/ω_high]. Throws std::invalid_argument
// when the band holds fewer than 4 points.
FractionalFit fit_fractional_order(const std::vector<double>& omega, const std::vector<std::complex<double>>& response,
                                   const Band& band, double delay_hint);

}  // namespace canalsim::linearize
