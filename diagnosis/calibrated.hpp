// What a calibration leaves open, in the units of the catalog's effects (issue 13: "an effect is
// material only where it exceeds what the calibration leaves open"). A scenario calibrated on a
// baseline (calibration/calibrate.hpp) knows its discharge coefficients, roughness, downstream
// setting and sensor offsets only to within their standard deviations; an effect that moves one
// of them by less than a few of those is the calibration's own tolerance, not a change of the canal.
#pragma once

#include <map>
#include <string>

#include "diagnosis/catalog.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::diagnosis {

// One standard deviation of `effect`'s departure from "no effect", in the unit of its parameter
// (for the multipliers: of the multiplier; for friction: of log n), that the calibration leaves
// open; 0 when no calibrated parameter maps onto the effect.
//   discharge_coefficient   relative std of cd_free / cd_submerged (the larger)
//   gate_leakage            that relative std × the mean operating opening [mm]
//   lateral_outflow         that relative std (a share of the inflow, like the flow's own error)
//   friction                relative std of manning_n (the largest over pools)
//   downstream_gate         std of downstream_opening_mm
//   sensor_offset           std of offset_mm and offset_y_dwe_mm combined (the primary sensor)
//   sensor_delay            std of sensor_delay_s
//   gate_rate_limit, sensor_quantization: 0 (not calibrated)
double calibration_uncertainty(Effect effect, const scenarios::Scenario& calibrated,
                               const std::map<std::string, double>& calibrated_std, double operating_opening_mm);

// Whether an effect refitted jointly with `added` (pipeline step 5) already spans what the
// calibration leaves open for `added`, so that `added` is judged without it: a free discharge
// coefficient takes up the discharge uncertainty that a leak is otherwise measured against (a
// leak within three of those deviations could be the calibrated coefficient's own error, but
// that error is now a parameter of the fit, and the leak's share of the flow, unlike the
// coefficient's, shrinks as the gate opens). Measured: a 1.08 mm leak beside a coefficient of
// 0.81 was refitted at 0.96 mm with the coefficient at 0.80, yet counted as within the
// calibration's tolerance. Not an outflow: a share of the inflow taken from the pool trades with
// the coefficient almost one for one, and with the rule a 2.9 % outflow was named beside a
// coefficient of 1.14 that had no outflow (realistic blind test, seed 1).
bool calibration_spanned_by(Effect added, Effect refitted);

// |parameter − no effect| in the measure calibration_uncertainty() uses.
double departure(Effect effect, double parameter);

}  // namespace canalsim::diagnosis
