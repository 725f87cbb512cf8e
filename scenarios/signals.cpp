#include "scenarios/signals.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace canalsim {
namespace {

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::vector<double> StepSignal::jumps(double from, double to) const {
  if (change_ == 0.0 || !(start_ > from && start_ <= to)) return {};
  return {start_};
}

RampSignal::RampSignal(double base, double change, double start, double duration)
    : base_(base), change_(change), start_(start), duration_(duration) {
  if (!(duration > 0.0) || !std::isfinite(duration)) {
    throw std::invalid_argument("ramp: duration must be > 0 s");
  }
}

double RampSignal::value(double t) const {
  if (t <= start_) return base_;
  if (t >= start_ + duration_) return base_ + change_;
  return base_ + change_ * (t - start_) / duration_;
}

SeriesSignal::SeriesSignal(std::vector<double> times, std::vector<double> values,
                           Interpolation interpolation)
    : times_(std::move(times)), values_(std::move(values)), interpolation_(interpolation) {
  if (times_.empty() || times_.size() != values_.size()) {
    throw std::invalid_argument("series signal: expected as many times as values (at least one), got " +
                                std::to_string(times_.size()) + " times and " +
                                std::to_string(values_.size()) + " values");
  }
  for (std::size_t i = 0; i < times_.size(); ++i) {
    if (!std::isfinite(times_[i]) || !std::isfinite(values_[i])) {
      throw std::invalid_argument("series signal: sample " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(times_[i] > times_[i - 1])) {
      throw std::invalid_argument("series signal: times must increase strictly (sample " +
                                  std::to_string(i) + ")");
    }
  }
}

SeriesSignal SeriesSignal::from_recording(const Recording& recording, const std::string& column,
                                          Interpolation interpolation) {
  const auto& t = recording.column(columns::time);
  const auto& v = recording.column(column);
  if (t.empty()) throw InputError(recording.source + ": no samples in column " + column);
  const double scale = si_scale_of_column(column);
  std::vector<double> values(v.size());
  std::transform(v.begin(), v.end(), values.begin(), [scale](double x) { return x * scale; });
  return SeriesSignal(t, std::move(values), interpolation);
}

double SeriesSignal::value(double t) const {
  if (t <= times_.front()) return values_.front();
  if (t >= times_.back()) return values_.back();
  // First sample strictly after t; t lies in [times_[i-1], times_[i]).
  const auto after = std::upper_bound(times_.begin(), times_.end(), t);
  const auto i = static_cast<std::size_t>(after - times_.begin());
  if (interpolation_ == Interpolation::zero_order_hold) return values_[i - 1];
  const double w = (t - times_[i - 1]) / (times_[i] - times_[i - 1]);
  return values_[i - 1] + w * (values_[i] - values_[i - 1]);
}

std::vector<double> SeriesSignal::jumps(double from, double to) const {
  std::vector<double> out;
  if (interpolation_ != Interpolation::zero_order_hold) return out;
  for (std::size_t i = 1; i < times_.size(); ++i) {
    if (times_[i] > from && times_[i] <= to && values_[i] != values_[i - 1]) out.push_back(times_[i]);
  }
  return out;
}

double si_scale_of_column(const std::string& column) {
  if (ends_with(column, "_mm")) return 1e-3;
  if (ends_with(column, "_lps")) return 1e-3;
  return 1.0;
}

}  // namespace canalsim
