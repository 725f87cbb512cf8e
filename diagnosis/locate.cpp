#include "diagnosis/locate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "diagnosis/residual_tests.hpp"

namespace canalsim::diagnosis {
namespace {

double mean_of(const std::vector<double>& x) {
  return x.empty() ? 0.0 : std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
}

double rms_of(const std::vector<double>& x) {
  return x.empty() ? 0.0 : std::sqrt(std::inner_product(x.begin(), x.end(), x.begin(), 0.0) / static_cast<double>(x.size()));
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// Accumulates residual samples by group name.
class Groups {
 public:
  void add(const std::string& name, double r) {
    auto& g = find(name);
    ++g.samples;
    g.mean += r;
    g.rms += r * r;
  }
  std::vector<GroupStat> finish() {
    for (auto& g : groups_) {
      if (g.samples == 0) continue;
      g.mean /= static_cast<double>(g.samples);
      g.rms = std::sqrt(g.rms / static_cast<double>(g.samples));
    }
    return groups_;
  }
  void declare(const std::string& name) { find(name); }

 private:
  GroupStat& find(const std::string& name) {
    for (auto& g : groups_) {
      if (g.name == name) return g;
    }
    groups_.push_back(GroupStat{name, 0, 0.0, 0.0});
    return groups_.back();
  }
  std::vector<GroupStat> groups_;
};

// Per-sample event labels of one recording.
struct SampleEvents {
  std::vector<bool> after_move, reversal, rising;
  std::vector<int> level_class;  // -1 low, 0 mid, +1 high
};

SampleEvents classify(const RecordingResiduals& r, const LocateOptions& o) {
  const std::size_t n = r.t.size();
  SampleEvents ev{std::vector<bool>(n, false), std::vector<bool>(n, false), std::vector<bool>(n, false),
                  std::vector<int>(n, 0)};
  const double h = r.period_s;
  double last_move = -1e300;
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0 && std::abs(r.u[k] - r.u[k - 1]) > 1e-9) last_move = r.t[k];
    ev.after_move[k] = r.t[k] - last_move <= o.move_horizon_s;
  }
  // Level trend from a centred moving average over the window; a reversal is a sign change of
  // the trend (a local extremum of the smoothed level), marked within half a window.
  const auto half = static_cast<std::size_t>(std::max(1.0, 0.5 * o.window_s / h));
  std::vector<double> smooth(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k >= half ? k - half : 0, b = std::min(n - 1, k + half);
    double s = 0.0;
    for (std::size_t j = a; j <= b; ++j) s += r.level[j];
    smooth[k] = s / static_cast<double>(b - a + 1);
  }
  for (std::size_t k = 1; k < n; ++k) ev.rising[k] = smooth[k] > smooth[k - 1];
  for (std::size_t k = 2; k < n; ++k) {
    if (ev.rising[k] != ev.rising[k - 1]) {
      const std::size_t a = k >= half ? k - half : 0, b = std::min(n - 1, k + half);
      for (std::size_t j = a; j <= b; ++j) ev.reversal[j] = true;
    }
  }
  const double lo = quantile(r.level, 0.25), hi = quantile(r.level, 0.75);
  for (std::size_t k = 0; k < n; ++k) ev.level_class[k] = r.level[k] < lo ? -1 : (r.level[k] > hi ? 1 : 0);
  return ev;
}

std::vector<MismatchWindow> windows_of(const RecordingResiduals& r, const SampleEvents& ev,
                                       double threshold, const LocateOptions& o) {
  const std::vector<double>& e = r.residuals.at(r.primary);
  const std::size_t n = e.size();
  const auto half = static_cast<std::size_t>(std::max(1.0, 0.5 * o.window_s / r.period_s));
  std::vector<double> moving(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k >= half ? k - half : 0, b = std::min(n - 1, k + half);
    double s = 0.0;
    for (std::size_t j = a; j <= b; ++j) s += e[j] * e[j];
    moving[k] = std::sqrt(s / static_cast<double>(b - a + 1));
  }
  std::vector<MismatchWindow> out;
  std::size_t k = 0;
  while (k < n) {
    if (moving[k] <= threshold) { ++k; continue; }
    const std::size_t a = k;
    while (k < n && moving[k] > threshold) ++k;
    const std::size_t b = k - 1;
    MismatchWindow w;
    w.recording = r.name;
    w.start_s = r.t[a];
    w.end_s = r.t[b];
    double s = 0.0;
    int moves = 0, reversals = 0, high = 0, low = 0, rising = 0;
    for (std::size_t j = a; j <= b; ++j) {
      s += e[j] * e[j];
      w.peak = std::max(w.peak, std::abs(e[j]));
      moves += ev.after_move[j];
      reversals += ev.reversal[j];
      high += ev.level_class[j] > 0;
      low += ev.level_class[j] < 0;
      rising += ev.rising[j];
    }
    const double len = static_cast<double>(b - a + 1);
    w.rms = std::sqrt(s / len);
    if (moves > 0.5 * len) w.events.push_back("after_gate_move");
    if (reversals > 0) w.events.push_back("reversal");
    if (high > 0.5 * len) w.events.push_back("high_level");
    if (low > 0.5 * len) w.events.push_back("low_level");
    w.events.push_back(rising > 0.5 * len ? "rising" : "falling");
    out.push_back(std::move(w));
  }
  return out;
}

}  // namespace

Status LocateOptions::validate() const {
  Validator check;
  check.require(window_s > 0.0 && window_s <= 600.0, "window_s", window_s, "(0, 600]");
  check.require(window_threshold > 0.0, "window_threshold", window_threshold, "> 0");
  check.require(move_horizon_s >= 0.0, "move_horizon_s", move_horizon_s, ">= 0");
  check.require(!(fir_order < 2 || fir_order > 1000), "fir_order", fir_order, "2..1000");
  check.require(band_z > 0.0, "band_z", band_z, "> 0");
  check.require(!(frequency_points < 8), "frequency_points", frequency_points, ">= 8");
  check.require(!(max_windows < 1), "max_windows", max_windows, ">= 1");
  return check.status();
}

FrequencyBand model_error_band(const std::vector<std::vector<double>>& inputs,
                               const std::vector<std::vector<double>>& residuals, double period_s,
                               const LocateOptions& o) {
  if (const Status status = o.validate(); !status) throw std::invalid_argument("locate options: " + status.message());
  if (inputs.size() != residuals.size()) throw std::invalid_argument("model_error_band: input and residual counts differ");
  const auto m = static_cast<std::size_t>(o.fir_order);
  std::size_t rows = 0;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (inputs[i].size() != residuals[i].size()) throw std::invalid_argument("model_error_band: lengths differ");
    if (inputs[i].size() > m) rows += inputs[i].size() - m + 1;
  }
  FrequencyBand band;
  if (rows < 2 * m) return band;
  // Normal equations: M is small (tens), the rows many; ΦᵀΦ is formed directly.
  Eigen::MatrixXd ptp = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  Eigen::VectorXd pte = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m));
  double ete = 0.0;
  std::vector<std::vector<double>> us, es;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    std::vector<double> u = inputs[i], e = residuals[i];
    const double mu = mean_of(u), me = mean_of(e);
    for (auto& v : u) v -= mu;
    for (auto& v : e) v -= me;
    for (std::size_t t = m - 1; t < u.size(); ++t) {
      Eigen::VectorXd phi(static_cast<Eigen::Index>(m));
      for (std::size_t k = 0; k < m; ++k) phi(static_cast<Eigen::Index>(k)) = u[t - k];
      ptp.noalias() += phi * phi.transpose();
      pte += phi * e[t];
      ete += e[t] * e[t];
    }
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(ptp);
  if (ldlt.info() != Eigen::Success || ptp.trace() <= 0.0) return band;
  const Eigen::VectorXd b = ldlt.solve(pte);
  const double sse = std::max(0.0, ete - 2.0 * b.dot(pte) + b.dot(ptp * b));
  const double sigma2 = sse / static_cast<double>(rows - m);
  const Eigen::MatrixXd cov = sigma2 * ldlt.solve(Eigen::MatrixXd::Identity(ptp.rows(), ptp.cols()));
  const double nyquist = 0.5 / period_s;
  const int nf = o.frequency_points;
  for (int j = 0; j < nf; ++j) {
    const double f = nyquist * (j + 0.5) / nf;
    const double w = 2.0 * std::numbers::pi * f * period_s;
    Eigen::VectorXd c(static_cast<Eigen::Index>(m)), s(static_cast<Eigen::Index>(m));
    for (std::size_t k = 0; k < m; ++k) {
      c(static_cast<Eigen::Index>(k)) = std::cos(w * static_cast<double>(k));
      s(static_cast<Eigen::Index>(k)) = -std::sin(w * static_cast<double>(k));
    }
    const double re = c.dot(b), im = s.dot(b);
    const double gain = std::hypot(re, im);
    // d|E|/db = (re c + im s)/|E|; at |E| = 0 use the larger of the two component variances.
    double var = 0.0;
    if (gain > 0.0) {
      const Eigen::VectorXd g = (re * c + im * s) / gain;
      var = g.dot(cov * g);
    } else {
      var = std::max(c.dot(cov * c), s.dot(cov * s));
    }
    band.frequency_hz.push_back(f);
    band.gain.push_back(gain);
    band.bound.push_back(o.band_z * std::sqrt(std::max(var, 0.0)));
  }
  // The contiguous run of frequencies above the bound with the largest summed excess.
  double best = 0.0, run = 0.0;
  std::size_t start = 0;
  for (std::size_t j = 0; j < band.gain.size(); ++j) {
    const double excess = band.gain[j] - band.bound[j];
    if (excess <= 0.0) { run = 0.0; continue; }
    if (run == 0.0) start = j;
    run += excess;
    if (run > best) {
      best = run;
      band.found = true;
      band.low_hz = band.frequency_hz[start];
      band.high_hz = band.frequency_hz[j];
    }
  }
  return band;
}

Mismatch locate(const std::vector<RecordingResiduals>& recs, const LocateOptions& o) {
  if (const Status status = o.validate(); !status) throw std::invalid_argument("locate options: " + status.message());
  Mismatch out;
  Groups regime, event, level;
  regime.declare("free");
  regime.declare("submerged");
  for (const char* name : {"after_gate_move", "settled", "rising", "falling", "reversal"}) event.declare(name);
  for (const char* name : {"low", "mid", "high"}) level.declare(name);
  std::map<std::string, std::pair<double, std::size_t>> channel_sq, channel_sum;
  std::vector<std::vector<double>> inputs, primaries;
  double pooled_sq = 0.0;
  std::size_t pooled_n = 0;
  for (const auto& r : recs) {
    const auto it = r.residuals.find(r.primary);
    if (it == r.residuals.end()) throw std::invalid_argument("locate: " + r.name + " has no residual of " + r.primary);
    const std::size_t n = it->second.size();
    if (r.t.size() != n || r.u.size() != n || r.level.size() != n || (!r.regime.empty() && r.regime.size() != n)) {
      throw std::invalid_argument("locate: " + r.name + ": series lengths differ");
    }
    for (double v : it->second) pooled_sq += v * v;
    pooled_n += n;
  }
  const double threshold = o.window_threshold * std::sqrt(pooled_sq / static_cast<double>(std::max<std::size_t>(pooled_n, 1)));
  for (const auto& r : recs) {
    const std::vector<double>& e = r.residuals.at(r.primary);
    const SampleEvents ev = classify(r, o);
    RecordingStat stat;
    stat.name = r.name;
    stat.operating_point_mm = r.operating_point_mm;
    stat.nrmse_percent = r.nrmse_percent;
    stat.rms = rms_of(e);
    stat.mean = mean_of(e);
    const ResidualTests tests = residual_tests(e, r.u);
    stat.white = tests.white();
    stat.uncorrelated = tests.uncorrelated();
    std::size_t free = 0;
    for (std::size_t k = 0; k < e.size(); ++k) {
      if (!r.regime.empty()) {
        const bool is_free = r.regime[k] < 0.5;
        free += is_free;
        regime.add(is_free ? "free" : "submerged", e[k]);
      }
      event.add(ev.after_move[k] ? "after_gate_move" : "settled", e[k]);
      event.add(ev.rising[k] ? "rising" : "falling", e[k]);
      if (ev.reversal[k]) event.add("reversal", e[k]);
      level.add(ev.level_class[k] < 0 ? "low" : (ev.level_class[k] > 0 ? "high" : "mid"), e[k]);
    }
    if (!r.regime.empty()) stat.free_fraction = static_cast<double>(free) / static_cast<double>(std::max<std::size_t>(e.size(), 1));
    for (const auto& [name, res] : r.residuals) {
      stat.channels.push_back(ChannelStat{name, rms_of(res), mean_of(res)});
      auto& sq = channel_sq[name];
      auto& sum = channel_sum[name];
      for (double v : res) { sq.first += v * v; sum.first += v; }
      sq.second += res.size();
      sum.second += res.size();
    }
    out.by_recording.push_back(std::move(stat));
    auto w = windows_of(r, ev, threshold, o);
    out.windows.insert(out.windows.end(), w.begin(), w.end());
    inputs.push_back(r.u);
    primaries.push_back(e);
  }
  std::sort(out.windows.begin(), out.windows.end(), [](const MismatchWindow& a, const MismatchWindow& b) {
    return a.rms * a.rms * (a.end_s - a.start_s + 1e-9) > b.rms * b.rms * (b.end_s - b.start_s + 1e-9);
  });
  if (out.windows.size() > static_cast<std::size_t>(o.max_windows)) out.windows.resize(static_cast<std::size_t>(o.max_windows));
  for (const auto& [name, sq] : channel_sq) {
    const double n = static_cast<double>(std::max<std::size_t>(sq.second, 1));
    out.by_channel.push_back(ChannelStat{name, std::sqrt(sq.first / n), channel_sum[name].first / n});
  }
  out.by_regime = regime.finish();
  out.by_event = event.finish();
  out.by_level = level.finish();
  if (!recs.empty()) out.band = model_error_band(inputs, primaries, recs.front().period_s, o);
  return out;
}

}  // namespace canalsim::diagnosis
