// Input signals for experiments: the gate command u(t) (or any other driven quantity) as a
// function of time. The simulator samples a signal at arbitrary times (its own time steps), so
// every signal answers value(t) for any real t, in SI units.
//
// Signals here: constant, step, ramp, and a series replayed from a recording column (linear or
// zero-order-hold interpolation). The PRBS of the paper's Section 4.3 is in scenarios/prbs.hpp.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/recording.hpp"

namespace canalsim {

// Common interface: the value at time t [s]. Implementations are immutable, so value() is safe
// to call from several threads.
class Signal {
 public:
  virtual ~Signal() = default;
  virtual double value(double t) const = 0;
  double operator()(double t) const { return value(t); }
  // The instants in (from, to] at which the value jumps, in increasing order (none for a
  // continuous signal). The simulator ends a time step at each, so that a gate switches when its
  // command does and not at the first step boundary after it (scenarios/simulate.cpp).
  virtual std::vector<double> jumps(double /*from*/, double /*to*/) const { return {}; }
};

using SignalPtr = std::shared_ptr<const Signal>;

class ConstantSignal final : public Signal {
 public:
  explicit ConstantSignal(double level) : level_(level) {}
  double value(double) const override { return level_; }

 private:
  double level_;
};

// base for t < start, base + change for t >= start.
class StepSignal final : public Signal {
 public:
  StepSignal(double base, double change, double start) : base_(base), change_(change), start_(start) {}
  double value(double t) const override { return t < start_ ? base_ : base_ + change_; }
  std::vector<double> jumps(double from, double to) const override;

 private:
  double base_, change_, start_;
};

// base until start, then a straight line reaching base + change at start + duration, held after.
class RampSignal final : public Signal {
 public:
  // Throws std::invalid_argument unless duration > 0.
  RampSignal(double base, double change, double start, double duration);
  double value(double t) const override;

 private:
  double base_, change_, start_, duration_;
};

enum class Interpolation {
  linear,           // straight line between neighbouring samples
  zero_order_hold,  // the latest sample at or before t (a sample-and-hold DAC)
};

// A sampled series. Before the first sample the first value holds; after the last, the last.
class SeriesSignal final : public Signal {
 public:
  // Throws std::invalid_argument unless times and values have the same length >= 1 and times
  // increase strictly and all values are finite.
  SeriesSignal(std::vector<double> times, std::vector<double> values,
               Interpolation interpolation = Interpolation::linear);

  // The column `column` of a recording against its t_s, converted to SI by the column's unit
  // suffix (si_scale_of_column). Throws InputError naming the recording when the column is
  // missing.
  static SeriesSignal from_recording(const Recording& recording, const std::string& column,
                                     Interpolation interpolation = Interpolation::linear);

  double value(double t) const override;
  // Zero-order hold: the sample times whose value differs from the one before; linear: none.
  std::vector<double> jumps(double from, double to) const override;
  std::size_t size() const { return times_.size(); }

 private:
  std::vector<double> times_;
  std::vector<double> values_;
  Interpolation interpolation_;
};

// Factor from a recording column's unit (named by its suffix) to SI: _mm -> 1e-3 m,
// _lps -> 1e-3 m^3/s, _s, _m, _m3s and anything else -> 1.
double si_scale_of_column(const std::string& column);

}  // namespace canalsim
