#include "calibration/replay.hpp"

#include <algorithm>
#include <optional>
#include <tuple>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>

#include "core/format.hpp"
#include "core/metadata.hpp"
#include "scenarios/simulate.hpp"

namespace canalsim::calibration {
namespace {

using scenarios::Scenario;

std::string format(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// The opening the experiment started from: the operating_opening_mm metadata (an error when it
// lies outside the controlled gate's range), else the first command.
double operating_point(const Recording& rec, const Scenario& scenario) {
  const std::optional<double> meta = metadata_number(rec, "operating_opening_mm");
  if (!meta) return rec.column(columns::gate_command).front();
  const scenarios::GateSpec* gate = controlled_gate(scenario);
  if (gate && *meta > gate->max_opening_m * 1e3) {
    throw InputError((rec.source.empty() ? std::string("recording") : rec.source) + ": metadata operating_opening_mm: " +
                     format_g(*meta) + " mm: expected an opening of the controlled gate, in [0, " +
                     format_g(gate->max_opening_m * 1e3) + "] mm");
  }
  return *meta;
}

// The recorded y_up_mm drives the head gate: asked for by the replay, or the scenario's own
// upstream (`kind = "recorded"`).
bool recorded_upstream(const Scenario& scenario, const ReplayOptions& o) {
  return o.use_recorded_upstream || scenario.upstream.kind == scenarios::UpstreamKind::recorded;
}

// The whole recording as a drive: time from 0, the command switched `command_lead_samples` early,
// and one extra row holding the operating point before the first sample so that the replay
// settles there.
Recording sampled_drive(const Recording& rec, double op, double lead_s, double period) {
  const double shift = rec.column(columns::time).front() + lead_s;
  Recording drive;
  drive.source = rec.source;
  drive.metadata = rec.metadata;
  for (std::size_t c = 0; c < rec.names.size(); ++c) {
    std::vector<double> v = rec.columns[c];
    const std::string& name = rec.names[c];
    if (name == columns::time) {
      for (auto& x : v) x -= shift;
      v.insert(v.begin(), v.front() - 1e-3 * period);
    } else {
      v.insert(v.begin(), name == columns::gate_command ? op : v.front());
    }
    drive.names.push_back(name);
    drive.columns.push_back(std::move(v));
  }
  return drive;
}

// A drive of the command alone: the operating point before t = 0, u[0] from t = 0, then each
// change at its reconstructed clock instant.
Recording clocked_drive(const Recording& rec, double op, const std::vector<double>& switches, double period) {
  const std::vector<double>& t = rec.column(columns::time);
  const std::vector<double>& u = rec.column(columns::gate_command);
  std::vector<double> dt{-1e-3 * period, 0.0}, du{op, u.front()};
  std::size_t j = 0;
  for (std::size_t k = 1; k < t.size(); ++k) {
    if (u[k] == u[k - 1]) continue;
    const double at = switches[j++] - t.front();
    if (at <= dt.back()) continue;
    dt.push_back(at);
    du.push_back(u[k]);
  }
  Recording drive;
  drive.source = rec.source;
  drive.metadata = rec.metadata;
  drive.set_meta("operating_opening_mm", format(op));
  drive.names = {columns::time, columns::gate_command};
  drive.columns = {dt, du};
  return drive;
}

// The clocked command drive with the recorded upstream level added: rows at every sample instant
// (levels as recorded, the command held) and at every switch instant (levels interpolated), so
// that the level follows the samples while the command switches at the reconstructed clock.
Recording clocked_drive_with_upstream(const Recording& rec, const Recording& clocked, double period) {
  const std::vector<double>& t = rec.column(columns::time);
  const std::vector<double>& y = rec.column(columns::upstream_level);
  const std::vector<double>& ct = clocked.column(columns::time);
  const std::vector<double>& cu = clocked.column(columns::gate_command);
  std::vector<double> times(ct);
  for (double x : t) times.push_back(x - t.front());
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end(), [&](double a, double b) { return b - a < 1e-9 * period; }),
              times.end());
  std::vector<double> u(times.size()), level(times.size());
  std::size_t j = 0, k = 0;
  for (std::size_t i = 0; i < times.size(); ++i) {
    while (j + 1 < ct.size() && ct[j + 1] <= times[i] + 1e-12) ++j;
    u[i] = cu[j];
    const double at = times[i] + t.front();
    while (k + 1 < t.size() && t[k + 1] <= at) ++k;
    const double f = k + 1 < t.size() ? std::clamp((at - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0) : 0.0;
    level[i] = k + 1 < t.size() ? y[k] + f * (y[k + 1] - y[k]) : y[k];
  }
  Recording drive = clocked;
  drive.names = {columns::time, columns::gate_command, columns::upstream_level};
  drive.columns = {times, u, level};
  return drive;
}

// Where the recording starts (Replay::initial_upstream_mm).
double initial_upstream(const Recording& rec) {
  if (const std::optional<double> meta = metadata_number(rec, "initial_y_up_mm")) return *meta;
  if (!rec.has(columns::upstream_level)) return std::numeric_limits<double>::quiet_NaN();
  const std::vector<double>& t = rec.column(columns::time);
  const std::vector<double>& u = rec.column(columns::gate_command);
  const std::vector<double>& y = rec.column(columns::upstream_level);
  double sum = 0.0;
  std::size_t k = 0;
  for (; k < y.size() && (k == 0 || (u[k] == u[0] && t[k] - t[0] <= 1.0)); ++k) sum += y[k];
  return sum / static_cast<double>(k);
}

}  // namespace

const scenarios::GateSpec* controlled_gate(const Scenario& s) {
  if (s.head_gate && s.head_gate->controlled) return &*s.head_gate;
  for (const auto& g : s.gates) {
    if (g.controlled) return &g;
  }
  return nullptr;
}

Replay prepare_replay(const Recording& rec, const Scenario& scenario, const ReplayOptions& o) {
  Replay p;
  p.period_s = scenario.sensors.period_s;
  const double period = p.period_s;
  p.name = rec.source.empty() ? rec.meta("experiment", "recording") : rec.source;
  const std::vector<double>& t = rec.column(columns::time);
  const std::vector<double>& u = rec.column(columns::gate_command);
  const std::size_t total = t.size();
  p.skip = std::min(total / 3, static_cast<std::size_t>(std::ceil(o.warmup_s / period - 1e-9)));
  auto tail = [&](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(p.skip), v.end());
  };
  p.t = tail(t);
  for (auto& x : p.t) x -= t.front();
  p.u = tail(u);
  p.n = p.t.size();
  p.n_fit = static_cast<std::size_t>(std::round(o.fit_fraction * static_cast<double>(p.n)));
  if (rec.has(columns::regime)) p.regime = tail(rec.column(columns::regime));
  for (const auto& c : o.channels) {
    if (rec.has(c)) p.data[c] = tail(rec.column(c));
  }
  p.operating_point_mm = operating_point(rec, scenario);
  p.initial_upstream_mm = initial_upstream(rec);
  p.drive = sampled_drive(rec, p.operating_point_mm, o.command_lead_samples * period, period);
  const bool upstream_replayed = recorded_upstream(scenario, o) && rec.has(columns::upstream_level);
  if (o.reconstruct_clock && (!upstream_replayed || o.clock_with_upstream)) {
    const std::vector<double> switches = command_switch_times(t, u);
    if (!switches.empty()) {
      p.drive = clocked_drive(rec, p.operating_point_mm, switches, period);
      if (upstream_replayed) p.drive = clocked_drive_with_upstream(rec, p.drive, period);
      p.clocked = true;
    }
  }
  return p;
}

Channels replay_true(const Scenario& scenario, const Replay& p, const ReplayOptions& o) {
  const bool own_start = o.start_at_recorded_level && std::isfinite(p.initial_upstream_mm) &&
                         (scenario.upstream.kind == scenarios::UpstreamKind::level ||
                          scenario.upstream.kind == scenarios::UpstreamKind::reservoir);
  Scenario started;
  if (own_start) {
    started = scenario;
    const double offset = scenario.sensors.offset_mm + scenario.sensors.offset_y_up_mm;
    started.upstream.level_m = std::max(1e-4, (p.initial_upstream_mm - offset) * 1e-3);
  }
  const Scenario& s = own_start ? started : scenario;
  scenarios::ExperimentSpec e;
  e.name = p.name;
  // A command logged a little beyond the gate's range (check_recordings) starts the gate at its limit.
  const scenarios::GateSpec* gate = controlled_gate(s);
  e.operating_opening_mm = gate ? std::clamp(p.operating_point_mm, 0.0, gate->max_opening_m * 1e3) : p.operating_point_mm;
  e.duration_s = (static_cast<double>(p.n + p.skip) - 0.5) * p.period_s;
  e.input.kind = scenarios::InputKind::constant;
  scenarios::SensorSpec ideal = s.sensors;
  ideal.resolution_mm = 0.0;
  ideal.noise_std_mm = 0.0;
  ideal.delay_s = 0.0;
  ideal.offset_mm = 0.0;
  ideal.offset_y_up_mm = ideal.offset_y_dw_mm = ideal.offset_y_dwe_mm = 0.0;
  e.sensors = ideal;
  scenarios::SimulateOptions so;
  so.drive.use_recorded_upstream = recorded_upstream(scenario, o) && p.drive.has(columns::upstream_level);
  // The recorded upstream level less its sensor's offsets is the water level that feeds the gate.
  const double up_offset = s.sensors.offset_mm + s.sensors.offset_y_up_mm;
  Recording corrected;
  if (so.drive.use_recorded_upstream && up_offset != 0.0) {
    corrected = p.drive;
    for (std::size_t c = 0; c < corrected.names.size(); ++c) {
      if (corrected.names[c] != columns::upstream_level) continue;
      for (double& v : corrected.columns[c]) v -= up_offset;
    }
  }
  so.drive.recording = so.drive.use_recorded_upstream && up_offset != 0.0 ? &corrected : &p.drive;
  so.settle_time = o.settle_time_s;
  so.warning = o.warning;
  const Recording r = scenarios::simulate(s, e, so);
  const auto at_recording_samples = [&](const std::string& c) {
    const std::vector<double>& all = r.column(c);
    std::vector<double> v(all.begin() + static_cast<std::ptrdiff_t>(std::min(p.skip, all.size())), all.end());
    v.resize(p.n, v.empty() ? 0.0 : v.back());
    return v;
  };
  Channels out;
  for (const auto& [c, y] : p.data) {
    if (r.has(c)) out[c] = at_recording_samples(c);
  }
  // The modelled flow through the controlled gate even where it was not recorded (a laboratory
  // logs levels): the diagnosis scales a lateral outflow by it. Costs compare recorded channels only.
  if (!out.count(columns::discharge) && r.has(columns::discharge)) out[columns::discharge] = at_recording_samples(columns::discharge);
  // The modelled flow regime likewise, so that a mismatch can be located by regime in recordings
  // that hold levels only.
  if (r.has(columns::regime)) out[columns::regime] = at_recording_samples(columns::regime);
  return out;
}

ChannelWeights channel_weights(const std::vector<Replay>& replays, const std::vector<std::string>& channels) {
  ChannelWeights w;
  for (const auto& c : channels) {
    double sum = 0.0;
    int count = 0;
    for (const auto& p : replays) {
      const auto it = p.data.find(c);
      if (it == p.data.end()) continue;
      const auto& y = it->second;
      const double m = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(y.size());
      double v = 0.0;
      for (double x : y) v += (x - m) * (x - m);
      sum += std::sqrt(v / static_cast<double>(y.size()));
      ++count;
    }
    if (count == 0) continue;
    const double floor = c == columns::discharge ? 0.05 : 0.5;
    w.scale[c] = std::max(sum / count, floor);
    w.weight[c] = 1.0 / (w.scale[c] * w.scale[c]);
  }
  return w;
}

namespace {

// A clock (period, phase) under which the switches at `changes` (indices of the samples where the
// command shows a change) fall inside their sample intervals [t[k-1], t[k]] to within a
// millionth of a sample, and how many of them fall exactly on the sample that shows them, t[k];
// -1 when it does not.
int switches_on_sample_instants(const std::vector<double>& t, const std::vector<std::size_t>& changes, double period,
                                double phase, double h) {
  const double eps = 1e-6 * h;
  int exact = 0;
  for (std::size_t k : changes) {
    const double s = phase + std::round((0.5 * (t[k - 1] + t[k]) - phase) / period) * period;
    if (s < t[k - 1] - eps || s > t[k] + eps) return -1;
    if (std::abs(s - t[k]) <= eps) ++exact;
  }
  return exact;
}

// A clock started with the recording (a tick at its first sample: a simulator, or a logger that
// starts the PRBS with its sampling) and commensurate with the sampling — the lab's 0.5 s clock
// and 0.13 s samples meet every 6.5 s — puts a switch exactly on a sample instant wherever a
// switch and a sample meet. The clock then sits at a corner of the feasible patch (those
// switches bind it), not at its centre: the centre is 4 ms early on the lab, and the level below
// the gate, which answers a gate move within a sample, is then replayed 0.13 mm RMS off (0.03 mm
// at the corner; the quantisation's 0.015). Which corner: a command is right-continuous — the sample
// at a switch instant shows the new value (a PRBS bit floor(t / T); a control loop that logs the
// command it applies at that tick) — so those switches fall on the sample that shows them, the
// end t[k] of their interval. (A recorder that logs the command of the interval before would put
// them on t[k-1] and be replayed 0.01 s late on the lab.) Candidates: the clocks through the
// first sample and the sample that shows one of the last changes, `period` telling how many
// periods lie between; the feasible one with the most switches exactly on the sample that shows
// them is kept when at least three are (chance does not put three switches of an unrelated clock
// within a millionth of a sample of a sample instant). A clock that did not start with the
// recording keeps the patch's centre.
std::optional<std::pair<double, double>> clock_on_sample_instants(const std::vector<double>& t,
                                                                   const std::vector<std::size_t>& changes, double period) {
  const double h = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  constexpr std::size_t kLastChanges = 64;
  const std::size_t n = changes.size();
  std::optional<std::pair<double, double>> best;
  int most = 2;
  for (std::size_t b = n - std::min(n, kLastChanges); b < n; ++b) {
    const double span = t[changes[b]] - t.front();
    const double periods = std::round(span / period);
    if (periods < 1.0) continue;
    const double p = span / periods;
    if (std::abs(p - period) > 1e-3 * period) continue;
    const int exact = switches_on_sample_instants(t, changes, p, t.front(), h);
    if (exact > most) {
      most = exact;
      best = std::make_pair(p, t.front());
    }
  }
  return best;
}

std::vector<double> search_command_clock(const std::vector<double>& t, const std::vector<double>& u) {
  std::vector<std::size_t> changes;
  for (std::size_t k = 1; k < u.size(); ++k) {
    if (u[k] != u[k - 1]) changes.push_back(k);
  }
  if (changes.size() < 8 || t.size() < 2) return {};
  // A command that changes at most samples (one that drifts, or is logged with noise) is no
  // clocked switching: there is no grid to find, and the search below would try every period
  // between half and twice the sample period at a tolerance fine enough for hundreds of switches.
  if (static_cast<double>(changes.size()) > 0.6 * static_cast<double>(u.size())) return {};
  const double h = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  double d_min = 1e300;
  for (std::size_t j = 1; j < changes.size(); ++j) d_min = std::min(d_min, t[changes[j]] - t[changes[j - 1]]);
  // Every grid point must fall in its change interval (t[k-1], t[k]], widened by a small
  // tolerance: a switch exactly at a sample instant (0.5 s clock, 0.13 s samples: every 6.5 s)
  // may show at that sample or the next, depending on rounding in the recorder.
  const double tol = 0.03 * h;
  // The same test in any order; the last change first, then the first, since a wrong period
  // fails soonest where it has accumulated most and a wrong phase where it starts: most of the
  // candidates below are rejected by one or two changes instead of a run of them.
  std::vector<std::size_t> order = changes;
  std::swap(order.front(), order.back());
  std::swap(order[1], order.back());
  auto feasible = [&](double period, double phase) {
    for (std::size_t k : order) {
      const double m = std::ceil((t[k - 1] - tol - phase) / period);
      const double s = phase + m * period;
      if (!(s >= t[k - 1] - tol && s <= t[k] + tol)) return false;
    }
    return true;
  };
  const std::size_t first = changes.front();
  std::vector<std::pair<double, double>> found;  // feasible (period, phase)
  // A period error δ moves the m-th grid point by m δ, so the step must be below the tolerance
  // divided by the number of periods the changes span (~500 for a 255 s PRBS at 0.5 s).
  const double span = t[changes.back()] - t[changes.front() - 1];
  const double period_step = std::max(1e-7, 0.5 * tol * std::max(d_min - h, 0.5 * h) / std::max(span, h));
  for (double period = std::max(0.5 * h, d_min - h); period <= d_min + h; period += period_step) {
    for (int i = 0; i <= 80; ++i) {
      const double phase = t[first - 1] - tol + (h + 2.0 * tol) * i / 80.0;
      if (feasible(period, phase)) found.emplace_back(period, phase);
    }
  }
  if (found.empty()) return {};
  // A finer grid can also fit (a few periods shorter than the clock pass by chance); the
  // longest consistent period is the clock. Its feasible patch is convex: take its centre.
  const double longest = found.back().first;
  double sum_period = 0.0, sum_phase = 0.0;
  int count = 0;
  for (const auto& [period, phase] : found) {
    if (longest - period > 1e-3 * longest) continue;
    sum_period += period;
    sum_phase += phase;
    ++count;
  }
  double period = sum_period / count, phase = sum_phase / count;
  if (!feasible(period, phase)) return {};
  if (const auto corner = clock_on_sample_instants(t, changes, period)) std::tie(period, phase) = *corner;
  std::vector<double> out;
  for (std::size_t k : changes) out.push_back(phase + std::ceil((t[k - 1] - tol - phase) / period) * period);
  return out;
}

}  // namespace

std::vector<double> command_switch_times(const std::vector<double>& t, const std::vector<double>& u) {
  // The search takes tens of milliseconds per recording and a calibration asks it again for every
  // problem it builds on the same recordings (each grid, the validation, the time-offset scan, the
  // written model's check): the answers are remembered, keyed by the command itself (an exact
  // comparison, not a hash), for the last few commands asked.
  constexpr std::size_t kRemembered = 64;
  using Key = std::pair<std::vector<double>, std::vector<double>>;
  static std::mutex guard;
  static std::map<Key, std::vector<double>> remembered;
  const auto finite = [](const std::vector<double>& v) { return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }); };
  if (!finite(t) || !finite(u)) return search_command_clock(t, u);  // the key's ordering needs numbers
  Key key{t, u};
  {
    const std::lock_guard<std::mutex> lock(guard);
    if (const auto it = remembered.find(key); it != remembered.end()) return it->second;
  }
  std::vector<double> switches = search_command_clock(t, u);
  const std::lock_guard<std::mutex> lock(guard);
  if (remembered.size() >= kRemembered) remembered.clear();
  remembered.emplace(std::move(key), switches);
  return switches;
}

std::vector<std::string> check_recordings(const Scenario& s, const std::vector<Recording>& recordings) {
  std::vector<std::string> problems;
  const scenarios::GateSpec* gate = controlled_gate(s);
  const double max_mm = gate ? gate->max_opening_m * 1e3 : std::numeric_limits<double>::infinity();
  const double h = s.sensors.period_s;
  if (recordings.empty()) problems.push_back("no recordings given");
  for (const Recording& rec : recordings) {
    const std::string name = rec.source.empty() ? "recording" : rec.source;
    std::vector<std::string> missing;
    for (const char* c : {columns::time, columns::gate_command, columns::level_downstream_end}) {
      if (!rec.has(c)) missing.push_back(c);
    }
    if (!missing.empty()) {
      std::string list;
      for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
      problems.push_back(name + ": missing channel(s) " + list);
      continue;
    }
    if (rec.size() < 50) {
      problems.push_back(name + ": " + std::to_string(rec.size()) + " samples, expected at least 50");
      continue;
    }
    const double hr = rec.sample_period();
    if (std::abs(hr - h) > 0.01 * h) {
      problems.push_back(name + ": sampled every " + format(hr) + " s, but the scenario's sensors sample every " +
                         format(h) + " s (sensors.period_s)");
    }
    // A logged command or position may read beyond the gate's range (a logger with an offset or a
    // gain of its own, tens of percent off; the gate stops at its limits, and the replay clamps it
    // there): up to 0.4 of the range. A column in another unit is off by a factor of ten or more
    // (cm, inches, m), one of another canal's gate likewise.
    const double slack = 0.4 * max_mm;
    for (const char* c : {columns::gate_command, columns::gate_position}) {
      if (!rec.has(c)) continue;
      const auto& v = rec.column(c);
      const auto& t = rec.column(columns::time);
      for (std::size_t k = 0; k < v.size(); ++k) {
        if (v[k] < -slack - 1e-9 || v[k] > max_mm + slack + 1e-9) {
          problems.push_back(name + ": " + c + " = " + format(v[k]) + " mm at t = " + format(t[k]) +
                             " s is outside the controlled gate's range 0.." + format(max_mm) + " mm (with 0.4 of it to spare)");
          break;
        }
      }
    }
    // A downstream level that never moves (a dead sensor, a column of zeros) has no response to
    // compare: its Nrmse (eq. 19) is undefined. (The upstream level may be constant: a fixed supply.)
    const auto& y = rec.column(columns::level_downstream_end);
    if (const auto [lowest, highest] = std::minmax_element(y.begin(), y.end()); *lowest == *highest) {
      problems.push_back(name + ": y_dwe_mm is " + format(*lowest) + " mm in every row: a level that never moves " +
                         "has no response to compare (a dead sensor?)");
    }
  }
  if (!gate) problems.push_back(s.source + ": the scenario has no gate with controlled = true to replay the command on");
  return problems;
}

}  // namespace canalsim::calibration
