#include "study/study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "reduced_models/metrics.hpp"
#include "study/explanations.hpp"
#include "study/text.hpp"

namespace canalsim::study {

using namespace canalsim::reduced;

Status StudyOptions::validate() const {
  Validator check;
  check.nested("StudyOptions.gamma", gamma.validate());
  check.require(gamma.first >= 0.0 && gamma.last <= 50.0, "StudyOptions.gamma", "expected within [0, 50]");
  check.require(threads >= 1, "StudyOptions.threads", "expected at least 1");
  check.require(prbs_clock_s > 0.0 && std::isfinite(prbs_clock_s), "StudyOptions.prbs_clock_s",
                "expected a positive clock period in s");
  check.require(prbs_stages >= 2 && prbs_stages <= 20, "StudyOptions.prbs_stages", "expected 2 to 20");
  return check.status();
}

std::vector<std::string> ExperimentRoles::all() const {
  std::vector<std::string> out;
  for (const auto* list : {&fit_all, &submerged, &free, &submerged_validation, &free_validation}) {
    for (const auto& n : *list) {
      if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
    }
  }
  return out;
}

ExperimentData study_data(const Recording& recording) {
  DataOptions options;
  const std::string op = recording.meta("operating_opening_mm");
  if (!op.empty()) {
    try {
      std::size_t used = 0;
      const double v = std::stod(op, &used);
      if (used != op.size() && op.find_first_not_of(" \t", used) != std::string::npos) throw 0;
      options.u0_mm = v;
    } catch (...) {
      throw InputError(recording.source + ": metadata operating_opening_mm: '" + op +
                       "', expected a number in mm");
    }
  }
  return prepare_data(recording, options);
}

namespace {

FitOptions fit_options(const StudyOptions& options, const std::string& stage) {
  FitOptions f;
  f.threads = options.threads;
  if (options.progress) {
    auto progress = options.progress;
    f.progress = [progress, stage](const ProgressReport& r) { progress({-1.0, stage + ": " + r.message}); };
  }
  return f;
}

std::vector<ExperimentData> pick(const std::map<std::string, ExperimentData>& data,
                                 const std::vector<std::string>& names) {
  std::vector<ExperimentData> out;
  for (const auto& n : names) {
    const auto it = data.find(n);
    if (it == data.end()) throw InputError("study: experiment " + n + " is missing");
    out.push_back(it->second);
  }
  return out;
}

}  // namespace

ModelTable build_model_table(const TableSpec& spec, const std::map<std::string, ExperimentData>& data,
                             const StudyOptions& options) {
  ModelTable table;
  table.spec = spec;
  const auto selected = pick(data, spec.experiments);
  const auto say = [&](const std::string& s) {
    if (options.progress) options.progress({-1.0, spec.id + " " + upper_name(spec.kind) + ": " + s});
  };
  const auto fo = fit_options(options, spec.id + " " + upper_name(spec.kind));
  if (uses_gamma(spec.kind)) {
    for (std::size_t j = 0; j < selected.size(); ++j) {
      say("gamma sweep at " + spec.experiments[j]);
      table.sweeps.push_back(gamma_sweep(spec.kind, {selected[j]}, fo, options.gamma));
      table.fits.push_back(table.sweeps.back().best_fit);
    }
    say("nominal gamma sweep");
    table.nominal_sweep = gamma_sweep(spec.kind, selected, fo, options.gamma);
    table.nominal = table.nominal_sweep->best_fit;
  } else {
    say("fits");
    table.fits = fit_each(spec.kind, selected, fo);
    say("nominal model");
    table.nominal = fit_nominal(spec.kind, selected, fo);
  }
  std::vector<Model> models;
  for (const auto& f : table.fits) models.push_back(f.model);
  table.uncertainty = uncertainty_indices(models, table.nominal.model);
  return table;
}

namespace {

ValidationTable validation_table(const std::string& id, const std::string& paper_key, const std::string& title,
                                 const std::vector<std::string>& experiments,
                                 const std::vector<std::string>& paper_experiments,
                                 const std::vector<const ModelTable*>& models,
                                 const std::map<std::string, ExperimentData>& data) {
  ValidationTable v;
  v.id = id;
  v.paper_key = paper_key;
  v.title = title;
  v.experiments = experiments;
  v.paper_experiments = paper_experiments;
  for (const auto* m : models) v.models.push_back(upper_name(m->spec.kind));
  for (const auto& op : experiments) {
    std::vector<Validation> row;
    for (const auto* m : models) row.push_back(validate_model(m->nominal.model, data.at(op)));
    v.results.push_back(std::move(row));
  }
  return v;
}

Spectrum prbs_spectrum(const ExperimentData& d, const StudyOptions& options) {
  Spectrum s;
  const double Tc = options.prbs_clock_s;
  const double N = std::pow(2.0, options.prbs_stages) - 1.0;
  const double period = N * Tc;
  const auto [lo, hi] = std::minmax_element(d.u_mm.begin(), d.u_mm.end());
  const double amplitude = 0.5 * (*hi - *lo);
  const double centre = 0.5 * (*hi + *lo);
  // One period from the first sample (the PRBS starts at t = 0).
  std::vector<double> x;
  for (std::size_t k = 0; k < d.size() && d.t_s[k] - d.t_s.front() < period - 1e-9; ++k) {
    x.push_back((d.u_mm[k] - centre) / amplitude);
  }
  const double two_pi = 2.0 * std::numbers::pi;
  // Half-power point of sinc²(f Tc) by bisection.
  double a = 1e-6, b = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double m = 0.5 * (a + b);
    const double sinc = std::sin(std::numbers::pi * m) / (std::numbers::pi * m);
    (sinc * sinc > 0.5 ? a : b) = m;
  }
  s.bandwidth_design_rad_s = two_pi * 0.5 * (a + b) / Tc;
  s.experiment = d.source;
  const double omega_max = 2.5 * two_pi / Tc;
  for (int k = 1;; ++k) {
    const double w = two_pi * k / period;
    if (w > omega_max) break;
    std::complex<double> sum = 0.0;
    const std::complex<double> step = std::polar(1.0, -w * d.h);
    std::complex<double> rot = 1.0;
    for (double v : x) {
      sum += v * rot;
      rot *= step;
    }
    const double f = w / two_pi;
    const double sinc = std::sin(std::numbers::pi * f * Tc) / (std::numbers::pi * f * Tc);
    s.omega.push_back(w);
    s.magnitude.push_back(std::abs(sum) * d.h);
    s.envelope.push_back(Tc * std::sqrt(N + 1.0) * std::abs(sinc));
    s.step.push_back(1.0 / w);
  }
  // Measured bandwidth: the lines of a sampled m-sequence scatter around the envelope (the
  // sampling period does not divide the clock period), so the magnitude is first smoothed (RMS over
  // ±4 lines); the bandwidth is where the smoothed magnitude first falls below its maximum / √2.
  std::vector<double> smooth(s.magnitude.size());
  const std::size_t half = 4;
  for (std::size_t i = 0; i < smooth.size(); ++i) {
    const std::size_t a0 = i >= half ? i - half : 0, a1 = std::min(smooth.size(), i + half + 1);
    double sum = 0.0;
    for (std::size_t k = a0; k < a1; ++k) sum += s.magnitude[k] * s.magnitude[k];
    smooth[i] = std::sqrt(sum / static_cast<double>(a1 - a0));
  }
  const double top = smooth.empty() ? 0.0 : *std::max_element(smooth.begin(), smooth.end());
  for (std::size_t i = 1; i < smooth.size(); ++i) {
    if (smooth[i] < top / std::sqrt(2.0) && smooth[i - 1] >= top / std::sqrt(2.0)) {
      const double f = (smooth[i - 1] - top / std::sqrt(2.0)) / (smooth[i - 1] - smooth[i]);
      s.bandwidth_measured_rad_s = s.omega[i - 1] + f * (s.omega[i] - s.omega[i - 1]);
      break;
    }
  }
  return s;
}

RegimeSummary regime_summary(const std::string& name, const Recording& rec, const ExperimentData& d) {
  RegimeSummary s;
  s.experiment = name;
  s.operating_opening_mm = d.u0_mm;
  if (!rec.has(columns::upstream_level) || !rec.has(columns::gate_position)) return s;
  const auto& y_up = rec.column(columns::upstream_level);
  const auto& x_up = rec.column(columns::gate_position);
  const auto& y_dwe = rec.column(columns::level_downstream_end);
  std::size_t free = 0;
  s.min_margin_mm = 1e300;
  s.max_margin_mm = -1e300;
  for (std::size_t k = 0; k < rec.size(); ++k) {
    const double margin = y_up[k] - free_flow_limit_mm(y_dwe[k], x_up[k]);
    s.min_margin_mm = std::min(s.min_margin_mm, margin);
    s.max_margin_mm = std::max(s.max_margin_mm, margin);
    if (rec.has(columns::regime)) {
      free += rec.column(columns::regime)[k] == static_cast<double>(RegimeCode::free) ? 1 : 0;
    } else {
      free += is_free_flow(y_up[k], y_dwe[k], x_up[k]) ? 1 : 0;
    }
  }
  s.free_fraction = rec.size() ? static_cast<double>(free) / static_cast<double>(rec.size()) : 0.0;
  return s;
}

}  // namespace

StudyResult run_study(const std::map<std::string, Recording>& recordings, const StudyOptions& options,
                      const ExperimentRoles& roles) {
  if (const Status status = options.validate(); !status) throw InputError(status.message());
  const auto start = std::chrono::steady_clock::now();
  std::map<std::string, ExperimentData> data;
  for (const auto& name : roles.all()) {
    const auto it = recordings.find(name);
    if (it == recordings.end()) throw InputError("study: experiment " + name + " is missing");
    data[name] = study_data(it->second);
    data[name].source = name;
  }
  StudyResult r;
  r.gamma = options.gamma;
  const std::vector<TableSpec> specs = {
      {"table1", "table1_LIOM", "LIOM fits (eq. 3–4)", ModelKind::liom, roles.fit_all},
      {"table2", "table2_LFOM", "LFOM fits (eq. 6–7)", ModelKind::lfom, roles.fit_all},
      {"table3", "table3_NLIOM_S", "NLIOM-S fits, submerged flow (eq. 14)", ModelKind::nliom_s, roles.submerged},
      {"table4", "table4_NLFOM_S", "NLFOM-S fits, submerged flow (eq. 15)", ModelKind::nlfom_s, roles.submerged},
      {"table6", "table6_NLIOM_F", "NLIOM-F fits, free flow (eq. 12)", ModelKind::nliom_f, roles.free},
      {"table7", "table7_NLFOM_F", "NLFOM-F fits, free flow (eq. 13)", ModelKind::nlfom_f, roles.free},
  };
  // Progress: the share of the six model tables done, with the stage the fits report.
  for (std::size_t k = 0; k < specs.size(); ++k) {
    StudyOptions table_options = options;
    if (options.progress) {
      const double done = static_cast<double>(k) / static_cast<double>(specs.size());
      table_options.progress = [&options, done](const ProgressReport& p) { options.progress({done, p.message}); };
    }
    r.tables.push_back(build_model_table(specs[k], data, table_options));
  }
  if (options.progress) options.progress({1.0, "validation and figures"});
  r.table5 = validation_table("table5", "table5_validation_submerged",
                              "Validation of the nominal models, submerged flow (Nrmse %)",
                              roles.submerged_validation, roles.submerged_validation_paper,
                              {&r.tables[0], &r.tables[1], &r.tables[2], &r.tables[3]}, data);
  r.table8 = validation_table("table8", "table8_validation_free",
                              "Validation of the nominal models, free flow (Nrmse %)",
                              roles.free_validation, roles.free_validation_paper,
                              {&r.tables[0], &r.tables[1], &r.tables[4], &r.tables[5]}, data);
  for (const auto& name : roles.fit_all) r.regimes.push_back(regime_summary(name, recordings.at(name), data.at(name)));
  r.spectrum = prbs_spectrum(data.at(roles.fit_all.front()), options);
  r.claims = conclusions(r);
  for (auto& claim : r.claims) claim.why = why_it_fails(claim, r);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace canalsim::study
