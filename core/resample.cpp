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
      .require(period_s >= kMinSamplePeriod && std::isfinite(period_s), "period_s", period_s,
               "a period of at least " + format_g(kMinSamplePeriod) + " s")
      .status();
}

namespace {

// The output grid and the filter's, as estimate_resample_cost and resample both need them.
struct Grids {
  double t0 = 0.0, duration = 0.0;
  double h_fine = 0.0;      // the fine grid's step: the median input step, or P if finer
  bool filter = false;      // P coarser than the record: anti-alias
  double rows = 0.0, fine_samples = 0.0, reach = 0.0;
};

Grids grids_for(const Recording& in, const ResampleOptions& options) {
  const std::string source = in.source.empty() ? "recording" : in.source;
  if (const Status status = options.validate(); !status) throw InputError(source + ": " + status.message());
  const auto& t = in.column(columns::time);
  if (t.size() < 2) throw InputError(source + ": expected at least two samples to resample");
  const double P = options.period_s;
  Grids g;
  g.t0 = t.front();
  g.duration = t.back() - g.t0;
  if (P > g.duration) {
    throw InputError(source + ": period " + format_g(P) + " s is longer than the recording (" +
                     format_g(g.duration) + " s)");
  }
  g.h_fine = std::min(median_step(t), P);
  g.filter = P > 1.0001 * g.h_fine;
  g.rows = std::floor(g.duration / P + 1e-9) + 1.0;
  g.fine_samples = g.filter ? std::floor(g.duration / g.h_fine) + 1.0 : 0.0;
  g.reach = std::ceil(12.0 * P / g.h_fine);
  return g;
}

std::size_t filtered_columns(const Recording& in, const ResampleOptions& options) {
  std::size_t n = 0;
  for (const auto& name : in.names) {
    const bool held = std::find(options.held_columns.begin(), options.held_columns.end(), name) !=
                      options.held_columns.end();
    n += name != columns::time && !held;
  }
  return n;
}

}  // namespace

ResampleCost estimate_resample_cost(const Recording& in, const ResampleOptions& options) {
  const Grids g = grids_for(in, options);
  ResampleCost cost;
  cost.rows = g.rows;
  cost.fine_samples = g.fine_samples;
  if (g.filter) {
    const auto columns = static_cast<double>(filtered_columns(in, options));
    cost.filter_operations = columns * (g.fine_samples + g.rows * (2.0 * g.reach + 1.0));
  }
  return cost;
}

Recording resample(const Recording& in, const ResampleOptions& options) {
  const std::string source = in.source.empty() ? "recording" : in.source;
  const Grids g = grids_for(in, options);
  const ResampleCost cost = estimate_resample_cost(in, options);
  if (!options.allow_large) {
    const auto refuse = [&](const std::string& verb, double value, const std::string& noun, double ceiling) {
      if (value <= ceiling) return;
      throw InputError(source + ": resampling " + format_g(g.duration) + " s at " + format_g(options.period_s) + " s " +
                       verb + " " + format_g(value, 3) + " " + noun + ", expected at most " + format_g(ceiling, 3) +
                       " (a longer --period, or pass --allow-long)");
    };
    refuse("writes", cost.rows, "rows", kMaxResampledRows);
    refuse("filters", cost.fine_samples, "samples of the fine grid", kMaxFineSamples);
    refuse("takes", cost.filter_operations, "filter operations", kMaxFilterOperations);
  }
  const auto& t = in.column(columns::time);
  const double P = options.period_s, t0 = g.t0, h_fine = g.h_fine;
  const bool filter = g.filter;
  const double fc = 0.385 / P, half = 12.0 * P;
  const auto n_out = static_cast<std::size_t>(g.rows);
  const auto n_fine = static_cast<std::size_t>(g.fine_samples);
  const auto reach = static_cast<std::ptrdiff_t>(g.reach);
  std::vector<double> t_out(n_out);
  for (std::size_t k = 0; k < n_out; ++k) t_out[k] = t0 + static_cast<double>(k) * P;

  Recording out;
  out.metadata = in.metadata;
  out.source = in.source;
  out.set_meta("resampled_period_s", format_g(P, 10));
  if (!in.meta("sampling_period_s").empty()) out.set_meta("sampling_period_s", format_g(P, 10));
  std::vector<double> fine(filter ? n_fine : 0);
  for (std::size_t c = 0; c < in.names.size(); ++c) {
    if (options.progress) {
      options.progress({static_cast<double>(c) / static_cast<double>(in.names.size()), "resampling " + in.names[c]});
    }
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
