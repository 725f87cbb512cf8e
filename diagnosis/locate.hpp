// Where a model and recordings disagree: in time (windows of large residual and the events they
// follow), in frequency (the band where an input→residual model-error model is significant), and
// by recording, operating point, flow regime, level and channel.
//
// Model-error model (Ljung, System Identification, Section 16.6): an FIR filter from the
// mean-removed input to the residual,
//   e(t) = Σ_{k=0}^{M-1} b_k ũ(t - k) + v(t),
// fitted by least squares over all recordings at once. Its frequency response
// E(ω) = Σ b_k e^{-iωkh} with the covariance σ_v² (ΦᵀΦ)⁻¹ of b gives, at each frequency, a
// standard deviation of |E| (first-order propagation); the model is wrong where |E| leaves its
// 99% region z·sd. The reported band is the contiguous stretch with the largest excess.
#pragma once

#include "core/status.hpp"

#include <map>
#include <string>
#include <vector>

namespace canalsim::diagnosis {

struct LocateOptions {
  double window_s = 2.0;          // moving-RMS window for time location; (0, 600]
  double window_threshold = 1.5;  // a window is "large" above this × the overall residual RMS; > 0
  double move_horizon_s = 8.0;    // "after a gate move": a command change this recently; >= 0
  int fir_order = 60;             // M of the model-error model; 2..1000
  double band_z = 2.58;           // confidence of the band (99%); > 0
  int frequency_points = 200;     // frequency grid from 0 to Nyquist; >= 8
  int max_windows = 12;           // windows reported; >= 1
  Status validate() const;
};

// Residuals of one recording, as the locator needs them (all vectors of the recording's length).
struct RecordingResiduals {
  std::string name;
  double operating_point_mm = 0.0;
  double period_s = 0.13;
  std::vector<double> t, u;           // time [s], gate command [mm]
  std::vector<double> level;          // recorded primary channel [mm]
  std::vector<double> regime;         // RegimeCode values (recorded, else modelled), or empty
  std::size_t fit_samples = 0;        // leading samples the explanation fitted (0 = half)
  std::string primary;                // the channel whose residual is located in time/frequency
  std::map<std::string, std::vector<double>> residuals;  // channel -> data - model
  std::map<std::string, std::vector<double>> recorded;   // level channel -> recorded series (noise estimates)
  double nrmse_percent = 0.0;         // primary-channel Nrmse (eq. 19) of the model
};

struct MismatchWindow {
  std::string recording;
  double start_s = 0.0, end_s = 0.0;
  double rms = 0.0, peak = 0.0;       // of the primary residual in the window
  std::vector<std::string> events;    // after_gate_move, reversal, high_level, low_level, rising, falling
};

struct FrequencyBand {
  bool found = false;
  double low_hz = 0.0, high_hz = 0.0;
  std::vector<double> frequency_hz, gain, bound;  // |E| and z·sd(|E|) on the grid
};

struct GroupStat {
  std::string name;
  std::size_t samples = 0;
  double rms = 0.0;    // RMS of the primary residual in the group
  double mean = 0.0;   // mean (bias) of the primary residual in the group
};

struct ChannelStat {
  std::string name;
  double rms = 0.0, mean = 0.0;
};

struct RecordingStat {
  std::string name;
  double operating_point_mm = 0.0;
  double nrmse_percent = 0.0;
  double rms = 0.0, mean = 0.0;      // primary residual
  double free_fraction = -1.0;       // share of free-flow samples; -1 without a regime column
  bool white = true, uncorrelated = true;
  std::vector<ChannelStat> channels;
};

struct Mismatch {
  std::vector<MismatchWindow> windows;   // largest first
  FrequencyBand band;
  std::vector<RecordingStat> by_recording;
  std::vector<GroupStat> by_regime;      // free / submerged
  std::vector<GroupStat> by_event;       // after_gate_move / settled / rising / falling / reversal
  std::vector<GroupStat> by_level;       // low / mid / high (recording's own quartiles)
  std::vector<ChannelStat> by_channel;   // pooled over recordings
};

// Throws std::invalid_argument on invalid options or inconsistent lengths.
Mismatch locate(const std::vector<RecordingResiduals>& recordings, const LocateOptions& options = {});

// The band alone (exposed for tests): FIR model-error model from u to e over several records.
FrequencyBand model_error_band(const std::vector<std::vector<double>>& inputs,
                               const std::vector<std::vector<double>>& residuals, double period_s,
                               const LocateOptions& options = {});

}  // namespace canalsim::diagnosis
