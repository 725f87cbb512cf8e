// Resampling a recording onto a uniform period: loggers time-stamp with jitter (and at rates of
// their own), the models need uniform samples.
//
// Measured columns are anti-aliased then sampled: linear interpolation onto a fine uniform grid
// (the recording's median step, or the new period if finer), then a zero-phase windowed-sinc
// low-pass (Blackman window, 24 periods long) evaluated at each output time, normalised by the
// weights inside the record (unit gain at DC and at the edges). Its cutoff is 0.385/P, its
// transition band 0.27/P – 0.5/P: what passes below 0.27/P keeps its amplitude (within 0.2 %),
// what lies above the new Nyquist frequency 0.5/P is attenuated by more than 70 dB instead of
// folding back. Upsampling (P not coarser than the recording) only interpolates linearly.
// Commands (the gate command u_mm) and codes (regime) are held: each output takes the last value
// at or before its time, since a command holds between its samples and a filter would ring.
#pragma once

#include <string>
#include <vector>

#include "core/progress.hpp"
#include "core/recording.hpp"
#include "core/status.hpp"

namespace canalsim {

struct ResampleOptions {
  double period_s = 0.0;
  std::vector<std::string> held_columns = {columns::gate_command, columns::regime};
  // Past the ceilings of ResampleCost (`--allow-long`).
  bool allow_large = false;
  ProgressCallback progress;  // the share of the columns done (may be empty)
  [[nodiscard]] Status validate() const;  // ok, or one line naming the field (core/status.hpp)
};

// What a resampling will take, known before it starts: the rows written, the samples of the fine
// grid the filter reads, and the filter's multiply-adds. Each has a ceiling (kMaxResampledRows:
// 5·10⁶ rows, a file of about 300 MB that the reader still takes; kMaxFineSamples: 5·10⁷, 400 MB;
// kMaxFilterOperations: 2·10¹⁰, about half a minute here) that resample() refuses to pass unless
// allow_large is set.
struct ResampleCost {
  double rows = 0.0;
  double fine_samples = 0.0;
  double filter_operations = 0.0;
};
inline constexpr double kMaxResampledRows = 5.0e6;
inline constexpr double kMaxFineSamples = 5.0e7;
inline constexpr double kMaxFilterOperations = 2.0e10;
ResampleCost estimate_resample_cost(const Recording& recording, const ResampleOptions& options);

// The recording on t_0 + k P, k = 0 … while ≤ the last time stamp; metadata kept, with
// `resampled_period_s` added and `sampling_period_s` set to P. Requires increasing t_s
// (read_recording checks it). Throws InputError naming the source when the record is too short,
// the period too long for it, or the cost past a ceiling (ResampleCost).
Recording resample(const Recording& recording, const ResampleOptions& options);

// Reads a recording whose time stamps only increase (any jitter); the reader for `resample`.
Recording read_unevenly_sampled_recording(const std::filesystem::path& file);

}  // namespace canalsim
