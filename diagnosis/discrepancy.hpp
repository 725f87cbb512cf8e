// Discrepancy model: when no catalog effect explains a residual, a data-driven correction that
// says what kind of physics is missing: a low-order linear filter from the gate command to one
// level channel's residual, fitted on the first part of each recording and shown to improve the
// held-out rest. It describes the residual; it is not physics.
//
// Output-error model (Ljung, System Identification, 2nd ed., Sections 4.2 and 10.2):
//   e(k) = c_r + B(q)/A(q) ũ(k - d),   ũ = u − u(0) of recording r (its operating point),
//   A(q) = 1 + a_1 q⁻¹ + … + a_na q⁻ⁿᵃ,   B(q) = b_0 + b_1 q⁻¹ + … + b_{nb−1} q⁻⁽ⁿᵇ⁻¹⁾,
// with one constant c_r per recording (a static offset per operating point). Each structure
// (na, nb, d) is initialised by least squares on the ARX form (Section 10.1) and improved by
// Gauss–Newton on the simulation error (Section 10.2): the filter is SIMULATED from ũ alone, never
// fed the measured residual's past (an autocorrelated residual predicts itself one step ahead
// whatever its cause). The structure with the least BIC of that error on the fitted parts wins;
// it must then improve the held-out parts.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/status.hpp"

namespace canalsim::diagnosis {

// One recording of one channel.
struct DiscrepancyRecording {
  std::vector<double> u;          // gate command [mm]
  std::vector<double> residual;   // recorded − model [mm], the length of u
  std::size_t n_fit = 0;          // leading samples fitted; the rest (at least one) is held out
};

struct DiscrepancyOptions {
  int max_poles = 2;              // na = 0..max_poles; range 0..4
  int max_numerator = 3;          // nb = 1..max_numerator coefficients of B; range 1..8
  double max_delay_s = 10.0;      // d = 0..max_delay_s / period, every sample; range [0, 60]
  double min_heldout_gain = 0.15; // held-out MSE must fall by this share; range (0, 1)
  Status validate() const;
};

struct DiscrepancyModel {
  std::string channel;
  // A filter from the command removes at least min_heldout_gain of the held-out MSE, and of
  // what the per-recording offsets alone leave. When the offsets alone do that, found stays false
  // and form is "static" with na = nb = 0 (the residual does not follow the command).
  bool found = false;
  std::string form = "none";      // static | dynamic | none (see below)
  int poles = 0, numerator = 0;   // na, nb
  double delay_s = 0.0;           // d · period
  std::vector<double> a, b;       // a_1..a_na, b_0..b_{nb−1}
  std::vector<double> offsets;    // c_r per recording [mm]
  double static_gain = 0.0;       // B(1)/A(1): mm of residual per mm of command at 0 Hz
  // |E(f)|, E = B(e^{iωh})/A(e^{iωh}) e^{−iωdh}: its maximum and the contiguous band around it
  // within 3 dB. "static" when the maximum is at 0 Hz and the band covers the frequencies the
  // command excites (90 % of its power): the correction acts as a gain (after the delay).
  double peak_hz = 0.0, band_low_hz = 0.0, band_high_hz = 0.0;
  double command_band_hz = 0.0;   // the frequency below which 90 % of the command's power lies
  double heldout_rms_before = 0.0, heldout_rms_after = 0.0;  // held-out residual RMS [mm]
  double heldout_share_removed = 0.0;  // 1 − MSE_after / MSE_before on the held-out parts
  double offsets_share_removed = 0.0;  // the same for the offsets alone
};

// Throws std::invalid_argument on invalid options, a period <= 0, no recordings, or a
// recording whose lengths differ, whose n_fit leaves no held-out part, or whose values are not finite.
DiscrepancyModel fit_discrepancy(const std::string& channel, const std::vector<DiscrepancyRecording>& recordings,
                                 double period_s, const DiscrepancyOptions& options = {});

}  // namespace canalsim::diagnosis
