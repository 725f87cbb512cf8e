// Truths canalsim's own model cannot represent exactly, for tests of fitting, calibration and
// diagnosis. A test that simulates its "recordings" with the very model it then fits proves only
// that the code agrees with itself: every modelling choice (grid, limiter, Courant number, gate
// law) cancels. These helpers make the truth differ the way real recordings do:
//
//   independent_truth()  the same canal simulated differently: more cells, the other limiter, a
//                        smaller Courant number, optionally the paper's simple gate laws (eqs.
//                        9, 11) instead of Swamee's (scenarios/variation.hpp);
//   realistic_levels()   level sensors as loggers have them: an offset, a drift, noise,
//                        quantisation on a lattice that does not pass through zero, sampling
//                        instants that jitter, and a time offset (either sign) between the
//                        command column and the level columns.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/laws.hpp"
#include "core/recording.hpp"
#include "scenarios/scenario.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::testing {

// The numerics of the truth (more cells, another limiter and Courant number, the simple gate
// laws) live in the library, where the realistic blind test uses them too.
using scenarios::TruthVariation;
using scenarios::independent_truth;

struct SensorRealism {
  double offset_mm = 0.0;          // added to every level
  double drift_mm_per_s = 0.0;     // added × t
  double noise_std_mm = 0.0;       // Gaussian
  double quantum_mm = 0.0;         // eq. 17 on a lattice offset by quantum_offset_mm (0 = none)
  double quantum_offset_mm = 0.0;
  double jitter_std_s = 0.0;       // each level is taken at t_k + δ_k (δ Gaussian), stamped t_k
  double time_offset_s = 0.0;      // the levels are those of t_k + time_offset_s (either sign)
  std::uint64_t seed = 7;
};

namespace detail {

// y at time t by linear interpolation of a uniformly sampled series (held beyond the ends).
inline double value_at(const std::vector<double>& t, const std::vector<double>& y, double at) {
  if (at <= t.front()) return y.front();
  if (at >= t.back()) return y.back();
  const double h = t[1] - t[0];
  const auto k = std::min(static_cast<std::size_t>((at - t.front()) / h), t.size() - 2);
  const double w = (at - t[k]) / (t[k + 1] - t[k]);
  return (1.0 - w) * y[k] + w * y[k + 1];
}

}  // namespace detail

inline bool is_level_column(const std::string& name) {
  return name == columns::upstream_level || name == columns::level_below_gate ||
         name == columns::level_downstream_end || name.rfind("y_check", 0) == 0;
}

// The recording with its level columns read by realistic sensors (the command, gate position
// and discharge columns are left as they are).
inline Recording realistic_levels(Recording rec, const SensorRealism& s) {
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const std::vector<double> t = rec.column(columns::time);
  for (std::size_t c = 0; c < rec.names.size(); ++c) {
    if (!is_level_column(rec.names[c])) continue;
    const std::vector<double> clean = rec.columns[c];
    for (std::size_t k = 0; k < t.size(); ++k) {
      const double at = t[k] + s.time_offset_s + (s.jitter_std_s > 0.0 ? s.jitter_std_s * unit(rng) : 0.0);
      double y = detail::value_at(t, clean, at) + s.offset_mm + s.drift_mm_per_s * (t[k] - t.front());
      if (s.noise_std_mm > 0.0) y += s.noise_std_mm * unit(rng);
      if (s.quantum_mm > 0.0) y = s.quantum_offset_mm + laws::quantise(y - s.quantum_offset_mm, s.quantum_mm);
      rec.columns[c][k] = y;
    }
  }
  return rec;
}

}  // namespace canalsim::testing
