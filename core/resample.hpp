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

#include "core/recording.hpp"
#include "core/status.hpp"

namespace canalsim {

struct ResampleOptions {
  double period_s = 0.0;
  std::vector<std::string> held_columns = {columns::gate_command, columns::regime};
  [[nodiscard]] Status validate() const;  // ok, or one line naming the field (core/status.hpp)
};

// The recording on t_0 + k P, k = 0 … while ≤ the last time stamp; metadata kept, with
// `resampled_period_s` added. Requires increasing t_s (read_recording checks it). Throws
// InputError naming the source when the record is too short or the period too long for it.
Recording resample(const Recording& recording, const ResampleOptions& options);

// Reads a recording whose time stamps only increase (any jitter); the reader for `resample`.
Recording read_unevenly_sampled_recording(const std::filesystem::path& file);

}  // namespace canalsim
