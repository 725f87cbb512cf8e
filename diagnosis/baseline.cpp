#include "diagnosis/baseline.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "calibration/observe.hpp"
#include "calibration/parameters.hpp"
#include "calibration/residual_breakdown.hpp"
#include "core/json.hpp"
#include "core/declared_units.hpp"
#include "core/errors.hpp"
#include "core/format.hpp"

namespace canalsim::diagnosis {
namespace {

// Share of the progress bar the calibration takes: on four 255.5 s laboratory baselines it
// replays about 480 recordings (30 Levenberg–Marquardt iterations with a finite-difference
// Jacobian each) in ~70 % of the wall time, the diagnosis of four recordings the rest
// (bench/README.md, "Diagnosis against a calibrated baseline").
constexpr double kCalibrationShare = 0.7;

std::string name_of(const Recording& r) { return r.source.empty() ? "recording" : r.source; }

std::vector<Recording> in_millimetres(const std::vector<Recording>& recordings) {
  std::vector<Recording> out;
  out.reserve(recordings.size());
  for (const Recording& r : recordings) out.push_back(canalsim::in_millimetres(r));
  return out;
}

// The first of the problems as one line; the user fixes it and reruns to see the next.
void throw_first(const std::vector<std::string>& problems, const std::string& context) {
  if (!problems.empty()) throw InputError(problems.front() + context);
}

}  // namespace

Status BaselineOptions::validate() const {
  Validator check;
  check.require(calibration_starts >= 1 && calibration_starts <= 10, "calibration_starts", calibration_starts, "1..10");
  check.require(calibration_iterations >= 1 && calibration_iterations <= 500, "calibration_iterations",
                calibration_iterations, "1..500");
  check.nested("diagnosis", diagnosis.validate());
  return check.status();
}

// calibrate() sets statistical_std always (without the grid check it is the whole std).
double left_open(const calibration::ParameterEstimate& p) { return p.statistical_std; }

std::map<std::string, double> calibrated_std_of(const calibration::Calibration& c) {
  std::map<std::string, double> out;
  for (const auto& p : c.parameters) {
    const double open = left_open(p);
    if (std::isfinite(open)) out[p.name] = open;
  }
  return out;
}

std::map<std::string, double> calibrated_std_of(const scenarios::Scenario& s) {
  if (s.calibrated_std.empty() && s.calibrated_std_alone.empty()) return {};
  const std::vector<calibration::Parameter> catalog = calibration::parameter_catalog(s);
  for (const auto& [table, deviations] : {std::pair{"std", &s.calibrated_std}, std::pair{"std_alone", &s.calibrated_std_alone}}) {
    for (const auto& [name, sd] : *deviations) {
      const std::string& key = name;  // clang 14 cannot capture a structured binding
      const bool known = std::any_of(catalog.begin(), catalog.end(), [&](const auto& p) { return p.name == key; });
      if (!known) {
        throw InputError(s.source + ": calibration." + table + "." + name + ": not a calibration parameter of " + s.name +
                         " (expected one of " + calibration::parameter_names(catalog) + ")");
      }
    }
  }
  return s.calibrated_std_alone.empty() ? s.calibrated_std : s.calibrated_std_alone;
}

std::map<std::string, double> calibrated_std_alone_of(const calibration::Calibration& c) {
  std::vector<std::size_t> determined;
  for (std::size_t i = 0; i < c.parameters.size(); ++i) {
    if (std::isfinite(left_open(c.parameters[i]))) determined.push_back(i);
  }
  const auto n = static_cast<Eigen::Index>(determined.size());
  if (c.correlation.size() != c.parameters.size() || n == 0) return calibrated_std_of(c);
  Eigen::MatrixXd R(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b < n; ++b) {
      R(a, b) = c.correlation[determined[static_cast<std::size_t>(a)]][determined[static_cast<std::size_t>(b)]];
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(R);
  if (llt.info() != Eigen::Success || !R.allFinite()) return calibrated_std_of(c);
  const Eigen::MatrixXd inverse = llt.solve(Eigen::MatrixXd::Identity(n, n));
  std::map<std::string, double> out;
  for (Eigen::Index a = 0; a < n; ++a) {
    const auto& p = c.parameters[determined[static_cast<std::size_t>(a)]];
    out[p.name] = left_open(p) / std::sqrt(std::max(inverse(a, a), 1.0));
  }
  return out;
}

std::map<std::string, double> baseline_rms_by_channel(const calibration::Calibration& c) {
  std::map<std::string, std::pair<double, int>> sums;
  for (const auto& f : c.fits) {
    if (f.validation || !calibration::is_level(f.channel)) continue;
    sums[f.channel].first += f.rms_after * f.rms_after;
    ++sums[f.channel].second;
  }
  std::map<std::string, double> out;
  for (const auto& [channel, s] : sums) out[channel] = std::sqrt(s.first / s.second);
  return out;
}

std::map<std::string, double> baseline_slow_rms_by_channel(const calibration::Calibration& c) {
  std::map<std::string, std::pair<double, std::size_t>> sums;
  for (const auto& s : c.series) {
    if (s.validation || !calibration::is_level(s.channel) || s.t.size() < 2 || s.calibrated.size() != s.recorded.size()) continue;
    for (double v : calibration::slower_than_fast_band(calibration::calibrated_residual(s), s.t[1] - s.t[0])) {
      sums[s.channel].first += v * v;
    }
    sums[s.channel].second += s.recorded.size();
  }
  std::map<std::string, double> out;
  for (const auto& [channel, s] : sums) out[channel] = std::sqrt(s.first / static_cast<double>(s.second));
  return out;
}

double baseline_rms_of(const calibration::Calibration& c, const std::string& primary) {
  double sq = 0.0;
  int n = 0;
  for (const auto& f : c.fits) {
    if (f.channel == primary && !f.validation) {
      sq += f.rms_after * f.rms_after;
      ++n;
    }
  }
  return n ? std::sqrt(sq / n) : 0.0;
}

std::vector<std::string> check_baseline(const std::vector<Recording>& baseline, const std::vector<Recording>& recordings) {
  std::vector<std::string> problems;
  if (baseline.empty()) problems.push_back("no baseline recordings given");
  if (recordings.empty()) problems.push_back("no recordings given");
  if (!problems.empty()) return problems;
  const Recording& first = recordings.front();
  const double h = first.sample_period();
  const std::string canal = first.meta("scenario");
  const auto differs = [](double a, double b) { return std::abs(a - b) > 0.01 * std::max(a, b); };
  for (const Recording& r : recordings) {
    if (differs(r.sample_period(), h)) {
      problems.push_back(name_of(r) + ": sampled every " + format_g(r.sample_period()) + " s, " + name_of(first) +
                         " every " + format_g(h) + " s");
    }
  }
  for (const Recording& b : baseline) {
    if (b.size() >= 2 && differs(b.sample_period(), h)) {
      problems.push_back(name_of(b) + ": sampled every " + format_g(b.sample_period()) + " s, the recordings every " +
                         format_g(h) + " s");
    }
    const std::string other = b.meta("scenario");
    if (!other.empty() && !canal.empty() && other != canal) {
      problems.push_back(name_of(b) + ": recorded on canal '" + other + "', the recordings on '" + canal +
                         "' (# scenario: metadata)");
    }
  }
  return problems;
}

std::string baseline_summary(const BaselineDiagnosis& r) {
  const calibration::Calibration& c = r.calibration;
  std::string out = "calibrated on " + std::to_string(r.baseline.size()) + " baseline recording(s):";
  for (const auto& f : r.baseline) out += " " + f;
  out += "\n";
  std::size_t width = 10;
  for (const auto& p : c.parameters) width = std::max(width, p.name.size() + 2);
  for (const auto& p : c.parameters) {
    std::string line = "  " + p.name + std::string(width - p.name.size(), ' ') + format_g(p.value, 5) + " ± " +
                       (std::isfinite(p.std) ? format_g(p.std, 2) : "not determined") + " " + p.unit + "  (was " +
                       format_g(p.start, 5) + ")" + (p.at_bound ? "  at a bound" : "");
    out += line + "\n";
  }
  out += "  weighted residual per sample " + format_g(c.cost_before, 3) + " -> " + format_g(c.cost_after, 3) + ", " +
         std::to_string(c.simulations) + " simulations, " + format_fixed(c.seconds, 1) + " s\n\n";
  return out;
}

nlohmann::json baseline_json(const BaselineDiagnosis& r) {
  using nlohmann::json;
  const calibration::Calibration& c = r.calibration;
  json parameters = json::array();
  for (const auto& p : c.parameters) {
    parameters.push_back({{"name", p.name}, {"unit", p.unit}, {"value", json_number(p.value)}, {"std", json_number(p.std)},
                          {"start", json_number(p.start)}, {"at_bound", p.at_bound}});
  }
  json fits = json::array();
  for (const auto& f : c.fits) {
    fits.push_back({{"recording", f.recording}, {"channel", f.channel}, {"rms_before", json_number(f.rms_before)},
                    {"rms_after", json_number(f.rms_after)}});
  }
  json unidentified = json::array();
  for (const auto& u : c.identifiability) unidentified.push_back({{"parameters", u.parameters}, {"reason", u.reason}});
  return json{{"files", r.baseline},           {"parameters", parameters},
              {"residual_before", json_number(c.cost_before)}, {"residual_after", json_number(c.cost_after)},
              {"fits", fits},                  {"not_identifiable", unidentified},
              {"simulations", c.simulations},  {"seconds", json_number(c.seconds)}};
}

std::vector<std::string> baseline_coverage(const std::vector<Recording>& baseline, const std::vector<Recording>& recordings) {
  const auto span = [](const Recording& r) {
    const auto& u = r.column(columns::gate_command);
    const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
    return std::pair<double, double>{*lo, *hi};
  };
  double lo = 1e300, hi = -1e300;
  for (const Recording& b : baseline) {
    if (!b.has(columns::gate_command) || b.size() == 0) continue;
    const auto [l, h] = span(b);
    lo = std::min(lo, l);
    hi = std::max(hi, h);
  }
  std::vector<std::string> warnings;
  if (lo > hi) return warnings;
  constexpr double kTolerance_mm = 2.0;
  for (const Recording& r : recordings) {
    if (!r.has(columns::gate_command) || r.size() == 0) continue;
    const auto [l, h] = span(r);
    if (l < lo - kTolerance_mm || h > hi + kTolerance_mm) {
      warnings.push_back(name_of(r) + ": gate command " + format_g(l, 4) + ".." + format_g(h, 4) + " mm, the baseline covered " +
                         format_g(lo, 4) + ".." + format_g(hi, 4) + " mm: the calibration may not hold there");
    }
  }
  return warnings;
}

calibration::CalibrateOptions baseline_calibration_options(const BaselineOptions& o) {
  calibration::CalibrateOptions c;
  c.parameters = o.parameters;
  c.starts = o.calibration_starts;
  c.max_iterations = o.calibration_iterations;
  c.threads = o.diagnosis.threads;
  c.grid_check = o.grid_check;
  c.replay = diagnosis_replay(o.diagnosis);
  c.replay.fit_fraction = 1.0;
  if (o.progress) {
    c.progress = [&o](const ProgressReport& r) {
      o.progress({r.fraction < 0.0 ? -1.0 : kCalibrationShare * r.fraction, "calibrating on the baseline: " + r.message});
    };
  }
  return c;
}

DiagnoseOptions against_calibration(const calibration::Calibration& calibration, DiagnoseOptions d) {
  d.calibrated_std = calibrated_std_alone_of(calibration);
  d.baseline_rms_mm = baseline_rms_of(calibration, d.primary);
  d.baseline_rms_by_channel = baseline_rms_by_channel(calibration);
  d.baseline_slow_rms_by_channel = baseline_slow_rms_by_channel(calibration);
  return d;
}

BaselineDiagnosis diagnose_with_baseline(const scenarios::Scenario& scenario, const std::vector<Recording>& baseline_in,
                                         const std::vector<Recording>& recordings_in, const BaselineOptions& o) {
  if (const Status status = o.validate(); !status) throw InputError("baseline diagnosis options: " + status.message());
  const std::vector<Recording> baseline = in_millimetres(baseline_in);
  const std::vector<Recording> recordings = in_millimetres(recordings_in);
  throw_first(check_baseline(baseline, recordings), "");
  throw_first(check_recordings(scenario, baseline), " (baseline; scenario " + scenario.name + ")");
  throw_first(check_recordings(scenario, recordings), " (scenario " + scenario.name + ")");

  BaselineDiagnosis out;
  for (const Recording& b : baseline) out.baseline.push_back(name_of(b));
  out.calibration = calibration::calibrate(scenario, baseline, {}, baseline_calibration_options(o));
  if (!out.calibration.ok) {
    out.calibration.series.clear();
    out.diagnosis.ok = false;
    out.diagnosis.message = "calibration on the baseline failed: " + out.calibration.message;
    return out;
  }
  DiagnoseOptions d = against_calibration(out.calibration, o.diagnosis);
  out.calibration.series.clear();  // plots of the baseline belong to `canalsim calibrate --report`
  d.progress = nullptr;
  if (o.progress) {
    d.progress = [&o](const ProgressReport& r) {
      o.progress({r.fraction < 0.0 ? -1.0 : kCalibrationShare + (1.0 - kCalibrationShare) * r.fraction, r.message});
    };
  }
  out.diagnosis = diagnose(out.calibration.calibrated, recordings, d);
  return out;
}

}  // namespace canalsim::diagnosis
