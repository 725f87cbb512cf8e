// Recordings in declared units (docs/recording-format.md, "Declared units"): a logger may record
// the gate command in encoder counts and the levels in centimetres, saying so in its metadata
//
//   # u_unit: counts            # y_unit: cm
//   # u_scale_mm_per_unit: 0.13 # y_scale_mm_per_unit: 10
//
// The models work in millimetres; this converts such a recording once, where it is read for
// replay or diagnosis, so that no verdict depends on the unit the logger used.
#pragma once

#include "core/recording.hpp"

namespace canalsim {

// The recording with u_mm and x_up_mm multiplied by u_scale_mm_per_unit and the level columns
// (y_up_mm, y_dw_mm, y_dwe_mm, y_check*) by y_scale_mm_per_unit; its unit metadata then say mm
// (so converting twice changes nothing). Throws InputError naming the recording and the key for a
// unit other than mm without its scale, or a scale that is not a positive number.
Recording in_millimetres(Recording recording);

}  // namespace canalsim
