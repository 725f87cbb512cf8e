// What the level sensors make of the water: the scenario's sensor model (paper eq. 17 resolution,
// a delay, an offset) applied to sampled true levels. Calibration and diagnosis both simulate a
// recording once with ideal sensors and then observe it through as many sensor models as they
// try, since a sensor changes nothing in the hydraulics.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "scenarios/scenario.hpp"

namespace canalsim::calibration {

// Named series of one recording or replay, in the recording's units (mm, l/s).
using Channels = std::map<std::string, std::vector<double>>;

// True for the level channels y_up_mm, y_dw_mm, y_dwe_mm and y_checkN_mm (the ones the sensor
// model acts on).
bool is_level(const std::string& channel);

// The faults of one level sensor (diagnosis/catalog.hpp reads them as instrument faults): its
// reading is gain·y(t − delay) + offset + drift·t, on its own lattice when resolution_mm ≥ 0.
struct ChannelFault {
  double offset_mm = 0.0;
  double delay_s = 0.0;             // added to SensorModel::delay_s (negative: it leads)
  double drift_mm_per_min = 0.0;    // from the first observed sample
  double gain = 1.0;                // on the level above the bed (the datum of a depth sensor)
  double resolution_mm = -1.0;      // < 0: the common SensorModel::resolution_mm
  double lattice_offset_mm = 0.0;   // the lattice is lattice_offset + k·resolution
};

// What the level sensors do to the true levels (gate position and flow sensors are ideal).
struct SensorModel {
  double resolution_mm = 0.0;
  double delay_s = 0.0;
  double offset_mm = 0.0;
  // Spread σ of (true level − model level), or 0. With a resolution r > 0, a prediction of the
  // reading is then its expectation E[Q(y + ε)], ε ~ N(0, σ²), instead of Q(y): when the model is
  // off by a fraction of a step, rounding it can pick the wrong step, while the expectation is
  // the mean-square-best prediction of a quantised reading at every σ (σ → 0 gives Q(y),
  // σ ≫ r gives y).
  double reading_spread_mm = 0.0;
  // Offsets of single level channels (y_up_mm, y_dw_mm, y_dwe_mm), added to offset_mm.
  std::map<std::string, double> channel_offset_mm = {};
  // Faults of single level sensors, by channel.
  std::map<std::string, ChannelFault> channel_fault = {};
  // The logged command leads every recorded channel by this much (two loggers' clocks, or a
  // command that acts late): every channel, levels, gate position and flow, is delayed.
  double clock_delay_s = 0.0;
};

// E[Q(y + ε)] for Q(v) = r·nint(v/r) and ε ~ N(0, σ²): Σ_m m r P(the reading is m r).
double expected_reading(double y, double resolution, double spread);
SensorModel sensor_model_of(const scenarios::SensorSpec& sensors);

// The level sensors of `m` applied to sampled true levels: delayed (linear interpolation between
// samples, the first sample held before the start), scaled, offset, drifted, then read (eq. 17, or
// its expectation when m.reading_spread_mm > 0). Other channels pass unchanged but for the clock
// delay, which shifts every channel.
Channels observe(const Channels& truth, const SensorModel& m, double period_s);

}  // namespace canalsim::calibration
