// Recordings in declared units (docs/recording-format.md, "Declared units"): a logger may record
// the gate command in encoder counts and the levels in centimetres, saying so in its metadata
//
//   # u_unit: counts            # y_unit: cm
//   # u_scale_mm_per_unit: 0.13 # y_scale_mm_per_unit: 10
//
// The models work in millimetres; this converts such a recording once, wherever it is read (fit,
// replay, diagnosis, an experiment's input file), so that no result depends on the unit the
// logger used.
#pragma once

#include <string>

#include "core/recording.hpp"

namespace canalsim {

// The unit a recording declares for its command ("u") or its levels ("y") and how many mm one
// of it is: ("mm", 1) without a declaration, ("unit", scale) for a scale without a unit name.
// Throws InputError naming the recording and the key for a unit other than mm without its scale,
// or a scale outside its range (core/metadata.hpp).
struct DeclaredUnit {
  std::string name = "mm";
  double mm_per_unit = 1.0;
};
DeclaredUnit declared_unit(const Recording& recording, const std::string& which);

// The recording with u_mm and x_up_mm multiplied by u_scale_mm_per_unit and the level columns
// (y_up_mm, y_dw_mm, y_dwe_mm, y_check*) by y_scale_mm_per_unit; its unit metadata then say mm
// (so converting twice changes nothing). Throws InputError naming the recording and the key as
// declared_unit does, and naming the row and column when a converted value exceeds
// kMaxRecordedMagnitude mm (the reader's check, applied after the units).
Recording in_millimetres(Recording recording);

}  // namespace canalsim
