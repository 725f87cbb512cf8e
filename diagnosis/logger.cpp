// The blind test's logger (blindtest.hpp as_logged): what instruments with concealed faults write
// of an experiment simulated with ideal sensors. It realises the catalog's sensor model
// (catalog.hpp: each row's edit of a SensorModel, its command map) with its own arithmetic, not
// with the diagnosis' observe(): a level's delay is read by cubic interpolation, a coarse instrument's
// lattice sits at an offset of its own (the same in each recording it writes), and noise enters
// before the reading is rounded.
#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <random>
#include <string>

#include "diagnosis/blindtest.hpp"
#include "scenarios/outside_catalog.hpp"

namespace canalsim::diagnosis {
namespace {

// Catmull–Rom interpolation of a uniformly sampled series at a fractional index; before the
// first sample the experiment was at its steady state, after the last it is held.
double cubic_at(const std::vector<double>& y, double index) {
  const auto last = static_cast<double>(y.size() - 1);
  if (index <= 0.0) return y.front();
  if (index >= last) return y.back();
  const auto k = static_cast<std::size_t>(index);
  const double f = index - static_cast<double>(k);
  const auto at = [&](std::ptrdiff_t i) {
    return y[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(i, 0, static_cast<std::ptrdiff_t>(y.size()) - 1))];
  };
  const auto i = static_cast<std::ptrdiff_t>(k);
  const double p0 = at(i - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
  return p1 + 0.5 * f * (p2 - p0 + f * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + f * (3.0 * (p1 - p2) + p3 - p0)));
}

// Linear interpolation, for the channels that move in steps (a gate position, a flow through it),
// on which a cubic would overshoot the gate's range.
double linear_at(const std::vector<double>& y, double index) {
  const auto last = static_cast<double>(y.size() - 1);
  if (index <= 0.0) return y.front();
  if (index >= last) return y.back();
  const auto k = static_cast<std::size_t>(index);
  return y[k] + (index - static_cast<double>(k)) * (y[k + 1] - y[k]);
}

std::vector<double> delayed(const std::vector<double>& y, double delay_samples, double (*at)(const std::vector<double>&, double)) {
  if (delay_samples == 0.0) return y;
  std::vector<double> out(y.size());
  for (std::size_t k = 0; k < y.size(); ++k) out[k] = at(y, static_cast<double>(k) - delay_samples);
  return out;
}

// The logged command of a gate that did `opening`: every command row maps a logged value to the
// opening affinely (catalog.cpp), so two points of the map invert it.
double logged_command(const Effect& effect, double parameter, double opening, double t_s) {
  const double at_zero = effect.kind->gate_saw(parameter, 0.0, t_s);
  const double slope = effect.kind->gate_saw(parameter, 1.0, t_s) - at_zero;
  return (opening - at_zero) / slope;
}

// Where a coarse instrument's lattice lies: its own, the same in every recording it writes (the
// instrument's zero, not the recording's), and anywhere within one step. Drawn from the fault
// itself — the channel and the step — so that all the recordings of one trial share it.
double lattice_origin(const std::string& channel, double step_mm) {
  std::mt19937_64 rng(std::hash<std::string>{}(channel) ^ std::bit_cast<std::uint64_t>(step_mm));
  return step_mm * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

}  // namespace

Recording as_logged(const Recording& ideal, const std::vector<ConcealedEffect>& concealed, const Logger& logger) {
  SensorModel faults;
  std::vector<std::pair<Effect, double>> command_faults;
  for (const ConcealedEffect& c : concealed) {
    const auto found = effect_from_name(c.effect);
    if (!found) continue;  // none, or physics outside the catalog (made by the simulation)
    const Effect& effect = *found;
    if (effect.kind->acts == Acts::readings) apply_effect(effect, c.value, faults);
    if (effect.kind->acts == Acts::command) command_faults.emplace_back(effect, c.value);
  }
  const std::vector<double>& t = ideal.column(columns::time);
  const double period = t.size() > 1 ? t[1] - t[0] : 1.0;
  std::mt19937_64 rng(logger.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Recording out = ideal;
  for (std::size_t c = 0; c < out.names.size(); ++c) {
    const std::string& name = out.names[c];
    std::vector<double>& v = out.columns[c];
    if (name == columns::time || name == columns::regime) continue;
    if (name == columns::gate_command) {
      for (const auto& [effect, p] : command_faults) {
        for (std::size_t k = 0; k < v.size(); ++k) v[k] = logged_command(effect, p, v[k], t[k] - t.front());
      }
      continue;
    }
    if (!calibration::is_level(name)) {
      v = delayed(v, faults.clock_delay_s / period, linear_at);
      continue;
    }
    const auto found = faults.channel_fault.find(name);
    const calibration::ChannelFault fault = found == faults.channel_fault.end() ? calibration::ChannelFault{} : found->second;
    const std::vector<double> level = delayed(v, (faults.clock_delay_s + faults.delay_s + fault.delay_s) / period, cubic_at);
    const double r = fault.resolution_mm >= 0.0 ? fault.resolution_mm : logger.resolution_mm;
    const double lattice = fault.resolution_mm >= 0.0 ? lattice_origin(name, r) : 0.0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      const double read = fault.gain * level[k] + faults.offset_mm + fault.offset_mm +
                          fault.drift_mm_per_min * (t[k] - t.front()) / 60.0 + logger.noise_std_mm * noise(rng);
      v[k] = r > 0.0 ? lattice + r * std::round((read - lattice) / r) : read;
    }
  }
  return out;
}

Recording simulate_concealed(const scenarios::Scenario& scenario, scenarios::ExperimentSpec e,
                             const std::vector<ConcealedEffect>& concealed, double inflow_m3s,
                             const scenarios::SimulateOptions& options, const scenarios::Simulator& simulator) {
  scenarios::Scenario s = scenario;
  scenarios::SensorSpec sensors = e.sensors.value_or(s.sensors);
  const Logger logger{sensors.noise_std_mm, sensors.resolution_mm, sensors.seed};
  sensors.noise_std_mm = 0.0;
  sensors.resolution_mm = 0.0;
  e.sensors = sensors;
  double backlash_mm = 0.0;
  for (const ConcealedEffect& effect : concealed) {
    conceal(effect, s, inflow_m3s);
    if (effect.effect == "gate_backlash") backlash_mm = effect.value;
  }
  const Recording ideal = backlash_mm > 0.0 ? scenarios::simulate_with_backlash(s, e, backlash_mm, options, simulator)
                        : simulator        ? simulator(s, e, options)
                                           : scenarios::simulate(s, e, options);
  return as_logged(ideal, concealed, logger);
}

}  // namespace canalsim::diagnosis
