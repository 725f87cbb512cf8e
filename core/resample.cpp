#include "core/resample.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/format.hpp"

namespace canalsim {
namespace {

// Linear interpolation of (t, v) at time x (t increasing, x inside [t.front(), t.back()]).
double interpolate(const std::vector<double>& t, const std::vector<double>& v, double x) {
  const auto it = std::upper_bound(t.begin(), t.end(), x);
  if (it == t.begin()) return v.front();
  if (it == t.end()) return v.back();
  const auto i = static_cast<std::size_t>(it - t.begin());
  const double w = (x - t[i - 1]) / (t[i] - t[i - 1]);
  return (1.0 - w) * v[i - 1] + w * v[i];
}

// The last value at or before time x.
double held(const std::vector<double>& t, const std::vector<double>& v, double x) {
  const auto it = std::upper_bound(t.begin(), t.end(), x + 1e-9 * std::max(1.0, std::abs(x)));
  return it == t.begin() ? v.front() : v[static_cast<std::size_t>(it - t.begin()) - 1];
}

double median_step(const std::vector<double>& t) {
  std::vector<double> steps(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) steps[i - 1] = t[i] - t[i - 1];
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

// Windowed-sinc low-pass kernel: sinc(2 fc τ) times a Blackman window of half-width `half`.
double kernel(double tau, double fc, double half) {
  if (std::abs(tau) >= half) return 0.0;
  const double x = 2.0 * fc * tau;
  const double sinc = x == 0.0 ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
  const double phase = std::numbers::pi * (tau / half + 1.0);  // 0 … 2π across the window
  const double window = 0.42 - 0.5 * std::cos(phase) + 0.08 * std::cos(2.0 * phase);
  return sinc * window;
}

}  // namespace

Status ResampleOptions::validate() const {
  return Validator()
      .require(period_s > 0.0 && std::isfinite(period_s), "period_s", period_s, "a positive number of seconds")
      .status();
}

Recording resample(const Recording& in, const ResampleOptions& options) {
  const std::string source = in.source.empty() ? "recording" : in.source;
  if (const Status status = options.validate(); !status) throw InputError(source + ": " + status.message());
  const auto& t = in.column(columns::time);
  if (t.size() < 2) throw InputError(source + ": expected at least two samples to resample");
  const double P = options.period_s;
  const double t0 = t.front(), duration = t.back() - t0;
  if (P > duration) {
    throw InputError(source + ": period " + format_g(P) + " s is longer than the recording (" +
                     format_g(duration) + " s)");
  }
  const auto n_out = static_cast<std::size_t>(std::floor(duration / P + 1e-9)) + 1;
  std::vector<double> t_out(n_out);
  for (std::size_t k = 0; k < n_out; ++k) t_out[k] = t0 + static_cast<double>(k) * P;

  // The fine grid and the filter (used when P is coarser than the recording's own step).
  const double h_fine = std::min(median_step(t), P);
  const bool filter = P > 1.0001 * h_fine;
  const double fc = 0.385 / P, half = 12.0 * P;
  const auto n_fine = static_cast<std::size_t>(std::floor(duration / h_fine)) + 1;
  if (filter && n_fine > 200'000'000) {
    throw InputError(source + ": " + std::to_string(n_fine) +
                     " samples at the recording's median step: too many to filter");
  }
  const auto reach = static_cast<std::ptrdiff_t>(std::ceil(half / h_fine));

  Recording out;
  out.metadata = in.metadata;
  out.source = in.source;
  out.set_meta("resampled_period_s", format_g(P, 10));
  std::vector<double> fine(filter ? n_fine : 0);
  for (std::size_t c = 0; c < in.names.size(); ++c) {
    const std::string& name = in.names[c];
    const auto& v = in.columns[c];
    std::vector<double> r(n_out);
    const bool hold = std::find(options.held_columns.begin(), options.held_columns.end(), name) !=
                      options.held_columns.end();
    if (name == columns::time) {
      r = t_out;
    } else if (hold) {
      for (std::size_t k = 0; k < n_out; ++k) r[k] = held(t, v, t_out[k]);
    } else if (!filter) {
      for (std::size_t k = 0; k < n_out; ++k) r[k] = interpolate(t, v, t_out[k]);
    } else {
      for (std::size_t j = 0; j < n_fine; ++j) fine[j] = interpolate(t, v, t0 + static_cast<double>(j) * h_fine);
      for (std::size_t k = 0; k < n_out; ++k) {
        const auto centre = static_cast<std::ptrdiff_t>(std::llround((t_out[k] - t0) / h_fine));
        const std::ptrdiff_t lo = std::max<std::ptrdiff_t>(0, centre - reach);
        const std::ptrdiff_t hi = std::min<std::ptrdiff_t>(static_cast<std::ptrdiff_t>(n_fine) - 1, centre + reach);
        double sum = 0.0, weights = 0.0;
        for (std::ptrdiff_t j = lo; j <= hi; ++j) {
          const double w = kernel(t_out[k] - (t0 + static_cast<double>(j) * h_fine), fc, half);
          sum += w * fine[static_cast<std::size_t>(j)];
          weights += w;
        }
        r[k] = sum / weights;
      }
    }
    out.names.push_back(name);
    out.columns.push_back(std::move(r));
  }
  return out;
}

Recording read_unevenly_sampled_recording(const std::filesystem::path& file) {
  RecordingReadOptions options;
  options.required = {columns::time};
  options.uniform_tolerance = std::numeric_limits<double>::infinity();
  return read_recording(file, options);
}

}  // namespace canalsim
