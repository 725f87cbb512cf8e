// The fit of each catalog effect in the scenario engine (scenario_engine.hpp).
#include "diagnosis/scenario_engine.hpp"

#include <algorithm>
#include <map>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "core/laws.hpp"

namespace canalsim::diagnosis::scenario_engine {
namespace {

using calibration::is_level;

// Gate position under a constant-speed actuator (paper eq. 16) driven by the replayed command
// (the drive's t_s/u_mm step function, exactly as the simulation replays it), at `samples`.
std::vector<double> rate_limited_position(const Recording& drive, const std::vector<double>& samples, double speed_mm_s) {
  const auto& ct = drive.column(columns::time);
  const auto& cu = drive.column(columns::gate_command);
  // An infinite speed (or inf * 0) is the ideal actuator: at the command (laws::rate_limited_move).
  const auto move = laws::rate_limited_move;
  std::vector<double> x;
  x.reserve(samples.size());
  double pos = cu.front(), now = ct.front();
  std::size_t j = 0;
  for (double s : samples) {
    while (j + 1 < ct.size() && ct[j + 1] <= s) {
      pos = move(pos, cu[j], speed_mm_s * (ct[j + 1] - now));
      now = ct[j + 1];
      ++j;
    }
    pos = move(pos, cu[j], speed_mm_s * (s - now));
    now = s;
    x.push_back(pos);
  }
  return x;
}


// Least-squares lattice step: with k_i = nint(y_i / r), r = Σ y_i k_i / Σ k_i². Levels of tens of
// millimetres sit ~100 steps from zero, so the scan's 0.005 mm grid is refined to ~1e-5 mm; a
// step off by 1% would put the model's lattice a whole step away from the recorded one.
double refine_lattice(const std::vector<const std::vector<double>*>& series, double r) {
  for (int it = 0; it < 4; ++it) {
    double yk = 0.0, kk = 0.0;
    for (const auto* y : series) {
      for (double v : *y) {
        const double k = std::round(v / r);
        yk += v * k;
        kk += k * k;
      }
    }
    if (!(kk > 0.0)) break;
    r = yk / kk;
  }
  return r;
}

// How closely the levels of the series that span at least `min_steps` steps of r sit on a
// lattice of step r: |mean exp(2πi y/r)| over them, 1 on the lattice; negative when no series
// spans that far.
double lattice_coherence(const std::vector<const std::vector<double>*>& series, double r, double min_steps) {
  double coherent = 0.0, total = 0.0;
  for (const auto* y : series) {
    const auto [lo, hi] = std::minmax_element(y->begin(), y->end());
    if (*hi - *lo < min_steps * r) continue;
    std::complex<double> sum = 0.0;
    for (double v : *y) sum += std::polar(1.0, 2.0 * std::numbers::pi * v / r);
    coherent += std::abs(sum);
    total += static_cast<double>(y->size());
  }
  return total > 0.0 ? coherent / total : -1.0;
}

}  // namespace

// Gauss–Newton with a secant Jacobian on the weighted residual vector: each step solves the
// one-parameter linearisation r(θ) ≈ r_best + J (θ − θ_best) between the best point and its
// nearest neighbour, within the catalog range.
Point Engine::fit_by_secant(const Effect& effect, const Point& start, int& sims) {
  const EffectKind& e = *effect.kind;
  std::vector<Point> pts;
  pts.push_back(start);
  // The probe is replayed whole: its first-order prospect and the effect's detection threshold
  // read the held-out part of its signature.
  {
    const ReplayScope probe(*this, Replays::probe);
    pts.push_back(evaluate(effect, std::clamp(e.theta_none + e.theta_probe, e.theta_low, e.theta_high)));
  }
  ++sims;
  const auto best_seen = [&pts] {
    return *std::min_element(pts.begin(), pts.end(), [](const Point& a, const Point& b) { return a.cost < b.cost; });
  };
  if (o_.screen_single_fits && screen_searches_) {
    // Most candidates explain nothing of a residual: their steps and final replay, each a
    // replay of every recording, are spared where the probe already shows it to first order.
    const double prospect = single_prospect(effect, pts.back());
    if (prospect < kProspectShare * o_.min_score) {
      stopped_at_probe_[effect.name()] = prospect;
      return best_seen();
    }
  }
  const ReplayScope search(*this, Replays::search);
  const double tol = 2e-3 * (e.theta_high - e.theta_low);
  while (sims < o_.max_evaluations) {
    const auto best = std::min_element(pts.begin(), pts.end(), [](const Point& a, const Point& b) { return a.cost < b.cost; });
    const Point* near = nullptr;
    for (const auto& q : pts) {
      if (&q == &*best) continue;
      if (!near || std::abs(q.theta - best->theta) < std::abs(near->theta - best->theta)) near = &q;
    }
    const double dtheta = best->theta - near->theta;
    if (dtheta == 0.0) break;
    double jj = 0.0, jr = 0.0;
    for (std::size_t k = 0; k < best->r.size(); ++k) {
      const double j = (best->r[k] - near->r[k]) / dtheta;
      jj += j * j;
      jr += j * best->r[k];
    }
    if (!(jj > 0.0)) break;
    // r = data - model, so the model's sensitivity is -J; the step minimises |r_best + J δ|².
    double step = -jr / jj;
    const double span = std::max(4.0 * std::abs(dtheta), 0.1 * (e.theta_high - e.theta_low));
    step = std::clamp(step, -span, span);
    const double next = std::clamp(best->theta + step, e.theta_low, e.theta_high);
    bool seen = false;
    for (const auto& q : pts) seen = seen || std::abs(q.theta - next) < tol;
    if (seen) break;
    pts.push_back(evaluate(effect, next));
    ++sims;
  }
  return best_seen();
}

double Engine::single_prospect(const Effect& effect, const Point& probe) const {
  const double step = probe.theta - effect.kind->theta_none;
  if (step == 0.0) return kCannotTell;
  double jj = 0.0, jr = 0.0;
  for (std::size_t k = 0; k < probe.r.size(); ++k) {
    const double j = (probe.r[k] - nominal_point_.r[k]) / step;
    jj += j * j;
    jr += j * nominal_point_.r[k];
  }
  if (!(jj > 0.0)) return kCannotTell;
  const double delta = -jr / jj;
  if (std::abs(delta) > kProspectSteps * std::abs(step) || !covers_heldout(probe)) return kCannotTell;
  const Costs after = costs(moved_along(nominal_, {{probe.prediction, nominal_, delta / step}}));
  const auto score = [](double before, double after_step) { return before > 0.0 ? (before - after_step) / before : 0.0; };
  return std::max(score(balanced(nominal_costs_, true), balanced(after, true)),
                  score(balanced_slow(nominal_costs_), balanced_slow(after)));
}

// The rate limit shows directly in the recorded gate position: fit the actuator speed to x_up
// against the command (golden section on θ = 1/v), then simulate once at the estimate.
Point Engine::rate_limit_from_position(const Effect& rate_limit, int& sims) {
  std::vector<std::vector<double>> instants;
  for (const auto& p : recs_) {
    std::vector<double> at(p.n);
    for (std::size_t k = 0; k < p.n; ++k) at[k] = static_cast<double>(p.skip + k) * period_;
    instants.push_back(std::move(at));
  }
  auto cost = [&](double theta) {
    double s = 0.0;
    for (std::size_t i = 0; i < recs_.size(); ++i) {
      const Prepared& p = recs_[i];
      const auto& x = p.data.at(columns::gate_position);
      const std::vector<double> m =
          rate_limited_position(p.drive, instants[i], theta <= 0.0 ? std::numeric_limits<double>::infinity() : 1.0 / theta);
      for (std::size_t k = 0; k < p.n_fit; ++k) s += (x[k] - m[k]) * (x[k] - m[k]);
    }
    return s;
  };
  const EffectKind& e = *rate_limit.kind;
  // Coarse logarithmic scan in speed first: the cost has a plateau at high speed.
  double best_theta = 0.0, best_cost = cost(0.0);
  for (double v = 0.5; v <= 400.0; v *= 1.1) {
    const double c = cost(1.0 / v);
    if (c < best_cost) { best_cost = c; best_theta = 1.0 / v; }
  }
  if (best_theta > 0.0) {
    double a = best_theta / 1.1, b = std::min(best_theta * 1.1, e.theta_high);
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    for (int it = 0; it < 40; ++it) {
      const double c = b - g * (b - a), d = a + g * (b - a);
      if (cost(c) < cost(d)) {
        b = d;
      } else {
        a = c;
      }
    }
    best_theta = 0.5 * (a + b);
  }
  if (best_theta <= 0.0) return nominal_point_;
  ++sims;
  return evaluate(rate_limit, best_theta);
}

// The largest resolution r whose lattice r·k holds the recorded levels of `channels`:
// |mean exp(2πi y/r)| near 1 over a channel that spans at least six lattice steps. The scenario's
// resolution when none does.
double Engine::lattice_resolution(const std::vector<std::string>& channels) const {
  // Differences from each series' first sample: on the lattice when the samples are (whatever
  // the lattice's offset), and only tens of steps from zero, so a coarse scan already finds the
  // right multiples.
  std::vector<std::vector<double>> diffs;
  for (const auto& p : recs_) {
    for (const auto& c : channels) {
      const auto it = p.data.find(c);
      if (it == p.data.end() || it->second.empty()) continue;
      const auto& y = it->second;
      std::vector<double> d(y.size());
      for (std::size_t k = 0; k < y.size(); ++k) d[k] = y[k] - y.front();
      diffs.push_back(std::move(d));
    }
  }
  std::vector<const std::vector<double>*> series;
  for (const auto& d : diffs) series.push_back(&d);
  const double largest = kind_named("sensor_quantization")->theta_high;
  for (double r = largest; r > sensors_.resolution_mm * 1.5; r -= 0.005) {
    if (lattice_coherence(series, r, 6.0) <= 0.9) continue;
    // A quantised channel's levels sit on its lattice exactly (to the digits a recording prints:
    // coherence above 0.98 down to a 0.1 mm step). Levels that dwell on a few values — a PRBS's
    // two, m steps apart — nearly sit on any lattice dividing their difference, which the scan's
    // loose test passes but its refinement does not bring near 1: the scan goes on below it.
    if (lattice_coherence(series, refine_lattice(series, r), 6.0) < 0.97) continue;
    // A lattice holds its submultiples too: a channel that moves by fewer than six steps of its
    // own lattice (an upstream level that hardly moves) is first seen on r/2 or r/3. The lattice is
    // the largest multiple of r the levels still sit on, over at least two of its steps.
    const double found = refine_lattice(series, r);
    double lattice = found;
    for (int m = 2; m * found <= largest; ++m) {
      if (lattice_coherence(series, m * found, 2.0) > 0.9) lattice = m * found;
    }
    return lattice == found ? found : refine_lattice(series, lattice);
  }
  return sensors_.resolution_mm;
}

// Where the lattice of resolution r sits for one recorded channel: the offset o in [0, r) of
// o + k·r, from the mean phase of exp(2πi y / r).
double Engine::lattice_phase(const std::string& channel, double r) const {
  if (!(r > 0.0)) return 0.0;
  std::complex<double> sum = 0.0;
  for (const auto& p : recs_) {
    const auto it = p.data.find(channel);
    if (it == p.data.end()) continue;
    for (double v : it->second) sum += std::polar(1.0, 2.0 * std::numbers::pi * v / r);
  }
  if (std::abs(sum) == 0.0) return 0.0;
  const double o = std::arg(sum) / (2.0 * std::numbers::pi) * r;
  return o < 0.0 ? o + r : o;
}

// Lattice coherence |mean exp(2πi (y - y_first)/r)| of the held-out recorded levels of `channels`.
double Engine::heldout_coherence(double r, const std::vector<std::string>& channels) const {
  std::complex<double> sum = 0.0;
  double count = 0.0;
  for (const auto& p : recs_) {
    for (const auto& c : channels) {
      const auto it = p.data.find(c);
      if (it == p.data.end() || p.n_fit >= it->second.size()) continue;
      const auto& y = it->second;
      for (std::size_t k = p.n_fit; k < y.size(); ++k) sum += std::polar(1.0, 2.0 * std::numbers::pi * (y[k] - y[p.n_fit]) / r);
      count += static_cast<double>(y.size() - p.n_fit);
    }
  }
  return count > 0.0 ? std::abs(sum) / count : 0.0;
}

std::vector<std::string> Engine::channels_of(const Effect& effect) const {
  if (!effect.channel.empty()) return {effect.channel};
  return level_channels_;
}

// Median of the level residuals on the fitted parts: the offset that explains them best in the
// least-absolute sense (robust to the transients a pure offset does not explain).
Point Engine::fit_median_offset(const Effect& effect) {
  std::vector<double> d;
  for (std::size_t i = 0; i < recs_.size(); ++i) {
    for (const auto& c : channels_of(effect)) {
      const auto& y = recs_[i].data.at(c);
      for (std::size_t k = 0; k < recs_[i].n_fit; ++k) d.push_back(y[k] - nominal_[i].at(c)[k]);
    }
  }
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return evaluate(effect, d.empty() ? 0.0 : d[d.size() / 2]);
}

// A delay re-observes the nominal simulation (no re-simulation): a 0.02 s grid over both signs
// (a negative delay is readings that lead the command: two loggers' clocks), then the vertex of
// the parabola through the best grid point and its neighbours.
Point Engine::fit_delay_grid(const Effect& effect) {
  const EffectKind& e = *effect.kind;
  Point best = nominal_point_;
  best.theta = 0.0;
  const int first = static_cast<int>(std::round(e.theta_low / 0.02)), last = static_cast<int>(std::round(e.theta_high / 0.02));
  for (int k = first; k <= last; ++k) {
    if (k == 0) continue;  // the nominal point
    Point p = evaluate(effect, 0.02 * k);
    if (p.cost < best.cost) best = std::move(p);
  }
  if (best.theta != 0.0 && best.theta > e.theta_low && best.theta < e.theta_high) {
    const double a = evaluate(effect, best.theta - 0.02).cost;
    const double c = evaluate(effect, best.theta + 0.02).cost;
    const double den = a - 2.0 * best.cost + c;
    if (den > 0.0) {
      Point p = evaluate(effect, best.theta + 0.01 * (a - c) / den);
      if (p.cost < best.cost) best = std::move(p);
    }
  }
  return best;
}

// An effect the readings depend on linearly (a drift, a gain): Gauss–Newton on the weighted
// residual vector with the signature (the prediction's change per unit of θ) of the expected
// readings, two steps (the second takes up what the lattice of the readings bends).
Point Engine::fit_linear(const Effect& effect) {
  const EffectKind& e = *effect.kind;
  Point best = nominal_point_;
  best.theta = e.theta_none;
  double theta = e.theta_none;
  for (int step = 0; step < 2; ++step) {
    const Point at = evaluate({{effect, theta}}, Readings::expected);
    const Point probe = evaluate({{effect, theta + e.theta_probe}}, Readings::expected);
    double jj = 0.0, jr = 0.0;
    for (std::size_t k = 0; k < at.r.size(); ++k) {
      const double j = (probe.r[k] - at.r[k]) / e.theta_probe;
      jj += j * j;
      jr += j * at.r[k];
    }
    if (!(jj > 0.0)) break;
    theta = std::clamp(theta - jr / jj, e.theta_low, e.theta_high);
    Point next = evaluate(effect, theta);
    if (next.cost < best.cost) best = std::move(next);
  }
  return best;
}

Point Engine::fit_lattice(const Effect& effect) { return evaluate(effect, lattice_resolution(channels_of(effect))); }

Point Engine::fit(const Effect& effect, int& sims) {
  switch (effect.kind->search) {
    case Search::median_offset: return fit_median_offset(effect);
    case Search::delay_grid: return fit_delay_grid(effect);
    case Search::linear: return fit_linear(effect);
    case Search::lattice: return fit_lattice(effect);
    case Search::rate_limit: return fit_gate_rate_limit(effect, sims);
    case Search::secant: break;
  }
  Point start = nominal_point_;
  start.theta = effect.kind->theta_none;
  return fit_by_secant(effect, start, sims);
}

// From the recorded gate position when every recording has it, else by re-simulation.
// Without a logged gate position (a laboratory logs levels) the speed must come from the levels:
// each trial speed is a re-simulation. The cost is flat above the speeds the command's steps
// ever reach and steep below, which a secant in θ = 1/v from the ideal gate cannot cross (it
// stopped at its probe); a scan of speeds a factor 2 apart over the catalog's range, then a
// golden-section search in log speed between the best scanned point's neighbours.
Point Engine::rate_limit_from_levels(const Effect& rate_limit, int& sims) {
  std::map<double, Point> seen;  // by θ
  const auto at = [&](double theta) -> const Point& {
    auto it = seen.find(theta);
    if (it == seen.end()) {
      it = seen.emplace(theta, evaluate(rate_limit, theta)).first;
      ++sims;
    }
    return it->second;
  };
  std::vector<double> speeds;
  for (double v = 40.0; v >= 1.0; v /= 2.0) speeds.push_back(v);
  // From the fastest speed down, the cost falls towards the actuator's speed and rises beyond it:
  // once it has risen twice in succession the best speed lies behind (an ideal gate's cost rises
  // from the first slow speed on, and the slowest ones, the most distorted, are not replayed).
  std::size_t best = 0;
  int rises = 0;
  for (std::size_t i = 0; i < speeds.size() && rises < 2; ++i) {
    const double cost = at(1.0 / speeds[i]).cost;
    if (i > 0) rises = cost > at(1.0 / speeds[i - 1]).cost ? rises + 1 : 0;
    if (cost < at(1.0 / speeds[best]).cost) best = i;
  }
  if (nominal_point_.cost <= at(1.0 / speeds[best]).cost) return nominal_point_;
  double a = std::log(speeds[std::min(best + 1, speeds.size() - 1)]), b = std::log(speeds[best > 0 ? best - 1 : 0]);
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  const auto cost_at = [&](double log_v) { return at(std::exp(-log_v)).cost; };
  for (int it = 0; it < 6 && b - a > 0.02; ++it) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (cost_at(c) < cost_at(d)) {
      b = d;
    } else {
      a = c;
    }
  }
  const auto lowest = std::min_element(seen.begin(), seen.end(),
                                       [](const auto& x, const auto& y) { return x.second.cost < y.second.cost; });
  return lowest->second;
}

Point Engine::fit_gate_rate_limit(const Effect& rate_limit, int& sims) {
  bool have_position = std::find(o_.channels.begin(), o_.channels.end(), columns::gate_position) != o_.channels.end();
  for (const auto& p : recs_) have_position = have_position && p.data.count(columns::gate_position) > 0;
  Point best;
  if (have_position) {
    best = rate_limit_from_position(rate_limit, sims);
  } else {
    const ReplayScope search(*this, Replays::search);
    best = rate_limit_from_levels(rate_limit, sims);
  }
  if (std::isnan(best.theta)) best.theta = 0.0;
  return best;
}

}  // namespace canalsim::diagnosis::scenario_engine
