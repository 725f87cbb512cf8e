#include "calibration/residual_breakdown.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "calibration/calibrate.hpp"
#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

// The slow band's edge (header comment; the fast band's is fast_band_edge_s).
constexpr double kSlowWindowS = 20.0;

bool is_level(const Series& s) { return s.channel.rfind("y_", 0) == 0; }

std::vector<double> residual(const Series& s, const std::vector<double>& model) {
  std::vector<double> r(s.recorded.size());
  for (std::size_t k = 0; k < r.size(); ++k) r[k] = s.recorded[k] - model[k];
  return r;
}

// Centred moving average over `window` samples (odd), truncated at the ends.
std::vector<double> moving_average(const std::vector<double>& x, std::size_t window) {
  const std::size_t n = x.size(), half = window / 2;
  std::vector<double> prefix(n + 1, 0.0), out(n);
  for (std::size_t k = 0; k < n; ++k) prefix[k + 1] = prefix[k] + x[k];
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t lo = k >= half ? k - half : 0, hi = std::min(n, k + half + 1);
    out[k] = (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo);
  }
  return out;
}

// The odd number of samples spanning `seconds`.
std::size_t samples_in(double seconds, double period_s) {
  return 2 * static_cast<std::size_t>(std::max(0.0, std::round(0.5 * seconds / period_s))) + 1;
}

double period_of(const Series& s) { return s.t.size() > 1 ? s.t[1] - s.t[0] : 1.0; }

// The filter bank's three parts of a residual: slow, mid, fast.
std::vector<std::vector<double>> frequency_parts(const std::vector<double>& r, const Series& s) {
  const std::vector<double> slow = moving_average(r, samples_in(kSlowWindowS, period_of(s)));
  const std::vector<double> smooth = slower_than_fast_band(r, period_of(s));
  std::vector<double> mid(r.size()), fast(r.size());
  for (std::size_t k = 0; k < r.size(); ++k) {
    mid[k] = smooth[k] - slow[k];
    fast[k] = r[k] - smooth[k];
  }
  return {slow, mid, fast};
}

// Seconds since the command last changed at each sample (+inf before the first change).
std::vector<double> time_since_switch(const Series& s) {
  std::vector<double> since(s.t.size(), std::numeric_limits<double>::infinity());
  double last = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < s.t.size(); ++k) {
    if (k > 0 && k < s.u.size() && s.u[k] != s.u[k - 1]) last = s.t[k];
    since[k] = s.t[k] - last;
  }
  return since;
}

// 0, 1, 2: the third of the recorded level's range-by-rank each sample is in.
std::vector<int> level_thirds(const Series& s) {
  std::vector<double> sorted = s.recorded;
  std::sort(sorted.begin(), sorted.end());
  const double low = sorted[sorted.size() / 3], high = sorted[(2 * sorted.size()) / 3];
  std::vector<int> third(s.recorded.size());
  for (std::size_t k = 0; k < third.size(); ++k) third[k] = s.recorded[k] < low ? 0 : s.recorded[k] < high ? 1 : 2;
  return third;
}

// The thirds of the time since a switch over every level series, as edges [s]: a PRBS on a
// half-second clock and a step every ten minutes both get three groups of equal weight.
std::pair<double, double> switch_time_thirds(const std::vector<Series>& series) {
  std::vector<double> all;
  for (const Series& s : series) {
    if (!is_level(s)) continue;
    const std::vector<double> since = time_since_switch(s);
    all.insert(all.end(), since.begin(), since.end());
  }
  if (all.empty()) return {0.0, 0.0};
  std::sort(all.begin(), all.end());
  return {all[all.size() / 3], all[(2 * all.size()) / 3]};
}

std::string seconds_text(double s) { return std::isfinite(s) ? format_g(s, 2) + " s" : "the end"; }

// Sums of one group: Σr, Σr² of the model and Σr² of each choice.
struct Sums {
  std::size_t samples = 0;
  double sum = 0.0, squares = 0.0;
  std::vector<double> choice_squares;
};

class Groups {
 public:
  explicit Groups(std::size_t choices) : choices_(choices) {}
  // Adds one sample to the group: the model's residual r and each choice's.
  void add(const std::string& axis, const std::string& name, double r, const std::vector<double>& choice_r) {
    Sums& g = at(axis, name);
    ++g.samples;
    g.sum += r;
    g.squares += r * r;
    for (std::size_t j = 0; j < choices_; ++j) g.choice_squares[j] += choice_r[j] * choice_r[j];
  }
  std::vector<BreakdownGroup> result(const std::vector<bool>& matched) const;

 private:
  Sums& at(const std::string& axis, const std::string& name) {
    for (auto& [key, sums] : groups_) {
      if (key.axis == axis && key.name == name) return sums;
    }
    groups_.push_back({{axis, name}, Sums{0, 0.0, 0.0, std::vector<double>(choices_, 0.0)}});
    return groups_.back().second;
  }
  struct Key {
    std::string axis, name;
  };
  std::size_t choices_;
  std::vector<std::pair<Key, Sums>> groups_;
};

std::vector<BreakdownGroup> Groups::result(const std::vector<bool>& matched) const {
  std::vector<BreakdownGroup> out;
  for (const auto& [key, g] : groups_) {
    BreakdownGroup b;
    b.axis = key.axis;
    b.name = key.name;
    b.samples = g.samples;
    const double n = static_cast<double>(std::max<std::size_t>(g.samples, 1));
    b.rms_mm = std::sqrt(g.squares / n);
    b.mean_mm = g.sum / n;
    for (std::size_t j = 0; j < choices_; ++j) {
      b.removed.push_back(!matched[j] || !(g.squares > 0.0) ? std::numeric_limits<double>::quiet_NaN()
                                                            : 1.0 - g.choice_squares[j] / g.squares);
    }
    out.push_back(std::move(b));
  }
  return out;
}

// The choice's series for the same recording and channel, or null.
const Series* counterpart(const std::vector<Series>& series, const Series& s) {
  for (const Series& c : series) {
    if (c.recording == s.recording && c.channel == s.channel && c.validation == s.validation &&
        c.calibrated.size() == s.recorded.size()) {
      return &c;
    }
  }
  return nullptr;
}

}  // namespace

ResidualBreakdown residual_breakdown(const std::vector<Series>& series, const std::vector<ChoiceSeries>& choices) {
  ResidualBreakdown out;
  for (const ChoiceSeries& c : choices) out.choices.push_back(c.name);
  const std::size_t m = choices.size();
  std::vector<bool> matched(m, true);
  Groups groups(m);
  const char* third_names[] = {"low third", "middle third", "high third"};
  const char* band_names[] = {"slow (> 20 s)", "mid (2 to 20 s)", "fast (< 2 s)"};
  const auto [soon, later] = switch_time_thirds(series);
  const std::string switch_names[] = {"< " + seconds_text(soon), seconds_text(soon) + " to " + seconds_text(later),
                                      "> " + seconds_text(later)};
  for (const Series& s : series) {
    if (!is_level(s) || s.recorded.empty() || s.calibrated.size() != s.recorded.size()) continue;
    const std::vector<double> r = calibrated_residual(s);
    std::vector<std::vector<double>> choice_r(m);
    for (std::size_t j = 0; j < m; ++j) {
      const Series* c = choices[j].series ? counterpart(*choices[j].series, s) : nullptr;
      matched[j] = matched[j] && c != nullptr;
      choice_r[j] = c ? residual(s, c->calibrated) : std::vector<double>(r.size(), 0.0);
    }
    const std::string op = s.recording + (s.validation ? " (validation)" : "");
    const std::vector<int> third = level_thirds(s);
    const std::vector<double> since = time_since_switch(s);
    std::vector<double> at_k(m);
    for (std::size_t k = 0; k < r.size(); ++k) {
      for (std::size_t j = 0; j < m; ++j) at_k[j] = choice_r[j][k];
      groups.add("operating point", op, r[k], at_k);
      groups.add("level", third_names[third[k]], r[k], at_k);
      groups.add("after a switch", switch_names[since[k] < soon ? 0 : since[k] < later ? 1 : 2], r[k], at_k);
      if (s.regime.size() == r.size()) {
        groups.add("regime", s.regime[k] == static_cast<double>(RegimeCode::submerged) ? "submerged" : "free", r[k], at_k);
      }
    }
    const std::vector<std::vector<double>> parts = frequency_parts(r, s);
    std::vector<std::vector<std::vector<double>>> choice_parts(m);
    for (std::size_t j = 0; j < m; ++j) choice_parts[j] = frequency_parts(choice_r[j], s);
    for (std::size_t band = 0; band < 3; ++band) {
      for (std::size_t k = 0; k < r.size(); ++k) {
        for (std::size_t j = 0; j < m; ++j) at_k[j] = choice_parts[j][band][k];
        groups.add("frequency", band_names[band], parts[band][k], at_k);
      }
    }
  }
  // The axes in the order of the header, each axis' groups in their own order (the recordings
  // as given).
  const std::vector<std::string> order = {"operating point", "regime", "free", "submerged",
                                          "level", "low third", "middle third", "high third",
                                          "after a switch", switch_names[0], switch_names[1], switch_names[2],
                                          "frequency", band_names[0], band_names[1], band_names[2]};
  const auto rank = [&order](const std::string& name) {
    return static_cast<std::size_t>(std::find(order.begin(), order.end(), name) - order.begin());
  };
  out.groups = groups.result(matched);
  std::stable_sort(out.groups.begin(), out.groups.end(), [&](const BreakdownGroup& a, const BreakdownGroup& b) {
    if (a.axis != b.axis) return rank(a.axis) < rank(b.axis);
    return rank(a.name) < rank(b.name);
  });
  return out;
}

std::vector<double> slower_than_fast_band(const std::vector<double>& residual, double period_s) {
  return moving_average(residual, samples_in(fast_band_edge_s, period_s));
}

std::vector<double> calibrated_residual(const Series& s) { return residual(s, s.calibrated); }

}  // namespace canalsim::calibration
