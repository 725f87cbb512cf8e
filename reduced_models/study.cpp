#include "reduced_models/study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "reduced_models/metrics.hpp"

namespace canalsim::reduced::study {

extern const char* const kPaperTablesJson;  // generated from data/paper_tables.json

namespace {

std::string fmt(double v, int digits) {
  if (!std::isfinite(v)) return v > 0 ? "∞" : (v < 0 ? "-∞" : "nan");
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, v);
  return buffer;
}

// A fitted parameter: fixed decimals, except a small non-zero value (the nonlinear models' scale
// K / H^γ at a large γ, ~1e-10) keeps three significant digits instead of printing as 0.0000.
std::string parameter_fmt(double v, int digits) {
  if (std::isfinite(v) && v != 0.0 && std::abs(v) < 0.01) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.3g", v);
    return buffer;
  }
  return fmt(v, digits);
}

// Δp of eq. (22) divides by the nominal parameter: a nominal γ of 0 (the linear form) makes it
// undefined, which the table says instead of printing a bare infinity.
std::string uncertainty_cell(double index) {
  return std::isfinite(index) ? fmt(100.0 * index, 2) : "∞ (nominal 0)";
}

std::string signed_fmt(double v, int digits) {
  if (!std::isfinite(v)) return fmt(v, digits);
  std::string out = v >= 0 ? "+" : "";
  out += fmt(v, digits);
  return out;
}

// "a", "a and b", "a, b and c".
std::string join_and(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += (i + 1 == items.size()) ? " and " : ", ";
    out += items[i];
  }
  return out;
}

std::string join_comma(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + items[i];
  return out;
}

std::string upper_name(ModelKind kind) {
  std::string n = model_name(kind);
  for (auto& c : n) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return n;
}

// Generic claim: `ok(paper_i, here_i)` for every place; the verdict names where it fails.
Claim make_claim(const std::string& table, const std::string& subject,
                 const std::vector<std::string>& where, const std::vector<double>& paper,
                 const std::vector<double>& here, const std::string& unit, bool show_sign,
                 const std::function<bool(double, double)>& ok) {
  if (where.size() != paper.size() || where.size() != here.size()) {
    throw std::invalid_argument("claim '" + subject + "': where, paper and here sizes differ");
  }
  std::vector<std::string> p, h, failed;
  for (std::size_t i = 0; i < where.size(); ++i) {
    p.push_back(show_sign ? signed_fmt(paper[i], 2) : fmt(paper[i], 2));
    h.push_back(show_sign ? signed_fmt(here[i], 2) : fmt(here[i], 2));
    if (!ok(paper[i], here[i])) failed.push_back(where[i]);
  }
  const std::string u = unit.empty() ? "" : " " + unit;
  Claim c;
  c.table = table;
  c.holds = failed.empty();
  c.text = subject + (where.empty() ? "" : " at " + join_and(where)) + ": paper " + join_and(p) +
           u + ", here " + join_and(h) + u + " — " +
           (c.holds ? std::string("holds.")
                    : "does not hold" + (failed.size() == where.size() ? std::string(".")
                                                                       : " (" + join_comma(failed) + ")."));
  return c;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

const nlohmann::json& paper_tables() {
  static const nlohmann::json tables = nlohmann::json::parse(kPaperTablesJson);
  return tables;
}

double paper_value(const std::string& pointer) {
  const auto& t = paper_tables();
  const nlohmann::json::json_pointer p(pointer);
  if (!t.contains(p) || !t.at(p).is_number()) {
    throw std::out_of_range("paper_tables.json: no number at " + pointer);
  }
  return t.at(p).get<double>();
}

Claim difference_claim(const std::string& table, const std::string& subject,
                       const std::vector<std::string>& where, const std::vector<double>& paper,
                       const std::vector<double>& here, const std::string& unit) {
  return make_claim(table, subject, where, paper, here, unit, true,
                    // Positive at the printed precision: a +0.00 tie does not count as beating.
                    [](double, double h) { return h >= 0.005; });
}

Claim range_claim(const std::string& table, const std::string& subject, const std::string& range_text,
                  const std::vector<std::string>& where, const std::vector<double>& paper,
                  const std::vector<double>& here, double lower, double upper) {
  return make_claim(table, subject + " (" + range_text + ")", where, paper, here, "", false,
                    [lower, upper](double, double h) { return h >= lower && h <= upper; });
}

Claim same_claim(const std::string& table, const std::string& subject, const std::string& paper,
                 const std::string& here) {
  Claim c;
  c.table = table;
  c.holds = paper == here;
  c.text = subject + ": paper " + paper + ", here " + here + " — " +
           (c.holds ? "holds." : "does not hold.");
  return c;
}

namespace {

// |here − paper| ≤ tolerance (absolute), or ≤ tolerance · |paper| when relative.
Claim close_claim(const std::string& table, const std::string& subject,
                  const std::vector<std::string>& where, const std::vector<double>& paper,
                  const std::vector<double>& here, double tolerance, bool relative,
                  const std::string& unit = "") {
  return make_claim(table, subject, where, paper, here, unit, false,
                    [tolerance, relative](double p, double h) {
                      return std::abs(h - p) <= tolerance * (relative ? std::abs(p) : 1.0);
                    });
}

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string StudyOptions::validate() const {
  if (const auto why = gamma.validate(); !why.empty()) return "StudyOptions.gamma: " + why;
  if (gamma.first < 0.0 || gamma.last > 50.0) return "StudyOptions.gamma: expected within [0, 50]";
  if (threads < 1) return "StudyOptions.threads: expected at least 1";
  if (!(prbs_clock_s > 0.0) || !std::isfinite(prbs_clock_s)) {
    return "StudyOptions.prbs_clock_s: expected a positive clock period in s";
  }
  if (prbs_stages < 2 || prbs_stages > 20) return "StudyOptions.prbs_stages: expected 2 to 20";
  return "";
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
    f.progress = [progress, stage](const ProgressReport& r) { progress(stage + ": " + r.message); };
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
    if (options.progress) options.progress(spec.id + " " + upper_name(spec.kind) + ": " + s);
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

const ModelTable& find_table(const StudyResult& r, ModelKind kind) {
  for (const auto& t : r.tables) {
    if (t.spec.kind == kind) return t;
  }
  throw std::logic_error("study: no table for " + model_name(kind));
}

std::size_t index_of(const std::vector<std::string>& v, const std::string& name) {
  const auto it = std::find(v.begin(), v.end(), name);
  if (it == v.end()) throw std::logic_error("study: " + name + " not in the list");
  return static_cast<std::size_t>(it - v.begin());
}

// The paper's model-table key of a table id.
std::string paper_fit(const ModelTable& t, const std::string& op, const std::string& field) {
  return "/" + t.spec.paper_key + "/fits/" + op + "/" + field;
}

// The paper's scale of a parameter: K of nonlinear models is K / H^γ (levels in mm).
double here_parameter(const Model& m, const std::string& name) {
  if (name == "K" && uses_upstream_level(m.kind)) return paper_gain(m);
  return get_parameter(m.p, name);
}

double here_nrmse(const ModelTable& t, const std::string& op) {
  return t.fits[index_of(t.spec.experiments, op)].nrmse.front();
}

std::string best_model(const ValidationTable& v, std::size_t row, bool paper) {
  std::string best;
  double best_value = -1e300;
  for (std::size_t m = 0; m < v.models.size(); ++m) {
    const double value = paper ? paper_value("/" + v.paper_key + "/" + v.paper_experiments[row] +
                                             "/" + v.models[m])
                               : v.results[row][m].nrmse;
    if (value > best_value) {
      best_value = value;
      best = v.models[m];
    }
  }
  return best;
}

double validation_here(const ValidationTable& v, std::size_t row, const std::string& model) {
  return v.results[row][index_of(v.models, model)].nrmse;
}
double validation_paper(const ValidationTable& v, std::size_t row, const std::string& model) {
  return paper_value("/" + v.paper_key + "/" + v.paper_experiments[row] + "/" + model);
}

}  // namespace

// Conclusions of a validation table (5 or 8): the best nominal model per experiment, and whether
// the nonlinear fractional model beats LFOM.
void add_validation_claims(const ValidationTable& v, const std::string& model, std::vector<Claim>& claims) {
  for (std::size_t row = 0; row < v.experiments.size(); ++row) {
    claims.push_back(same_claim(v.id, "Best nominal model in validation at " + v.experiments[row] +
                                          " (paper " + v.paper_experiments[row] + ")",
                                best_model(v, row, true), best_model(v, row, false)));
  }
  std::vector<double> p, h;
  for (std::size_t row = 0; row < v.experiments.size(); ++row) {
    p.push_back(validation_paper(v, row, model) - validation_paper(v, row, "LFOM"));
    h.push_back(validation_here(v, row, model) - validation_here(v, row, "LFOM"));
  }
  claims.push_back(difference_claim(v.id, "In validation the nominal " + model + " beats the nominal LFOM",
                                    v.experiments, p, h));
}

std::vector<Claim> conclusions(const StudyResult& r) {
  std::vector<Claim> claims;
  const auto& liom = find_table(r, ModelKind::liom);
  const auto& lfom = find_table(r, ModelKind::lfom);
  const auto& nliom_s = find_table(r, ModelKind::nliom_s);
  const auto& nlfom_s = find_table(r, ModelKind::nlfom_s);
  const auto& nliom_f = find_table(r, ModelKind::nliom_f);
  const auto& nlfom_f = find_table(r, ModelKind::nlfom_f);

  // Per-op columns of a table: paper and here.
  const auto column = [](const ModelTable& t, const std::string& name, bool paper) {
    std::vector<double> out;
    for (std::size_t j = 0; j < t.spec.experiments.size(); ++j) {
      out.push_back(paper ? paper_value(paper_fit(t, t.spec.experiments[j], name))
                          : (name == "nrmse" ? t.fits[j].nrmse.front()
                                             : here_parameter(t.fits[j].model, name)));
    }
    return out;
  };
  // Nrmse gain of table a over table b at b's ops shared with a.
  const auto gain = [&](const ModelTable& a, const ModelTable& b, bool paper) {
    std::vector<double> out;
    for (const auto& op : a.spec.experiments) {
      out.push_back(paper ? paper_value(paper_fit(a, op, "nrmse")) - paper_value(paper_fit(b, op, "nrmse"))
                          : here_nrmse(a, op) - here_nrmse(b, op));
    }
    return out;
  };
  const auto nominal_loss = [&](const ModelTable& t, bool paper) {
    std::vector<double> out;
    for (std::size_t j = 0; j < t.spec.experiments.size(); ++j) {
      const auto& op = t.spec.experiments[j];
      out.push_back(paper ? paper_value(paper_fit(t, op, "nrmse")) -
                                paper_value("/" + t.spec.paper_key + "/nominal/nrmse/" + op)
                          : t.fits[j].nrmse.front() - t.nominal.nrmse[j]);
    }
    return out;
  };
  // Table 1.
  claims.push_back(close_claim("table1", "The LIOM gain K agrees with the paper's within 30 %",
                               liom.spec.experiments, column(liom, "K", true), column(liom, "K", false),
                               0.30, true, "mm/mm"));
  claims.push_back(close_claim("table1", "The LIOM delay L agrees with the paper's within 1 s",
                               liom.spec.experiments, column(liom, "L", true), column(liom, "L", false),
                               1.0, false, "s"));
  claims.push_back(close_claim("table1", "The LIOM fit quality Nrmse agrees with the paper's within 10 points",
                               liom.spec.experiments, column(liom, "nrmse", true),
                               column(liom, "nrmse", false), 10.0, false, "%"));
  claims.push_back(difference_claim("table1", "The individual LIOM fits beat the nominal LIOM (Nrmse)",
                                    liom.spec.experiments, nominal_loss(liom, true), nominal_loss(liom, false)));
  claims.push_back(difference_claim(
      "table1", "The LIOM time constant varies more than its gain across op1–op4 (ΔT − ΔK, eq. 22)",
      {"op1–op4"}, {paper_value("/table1_LIOM/uncertainty_pct/T") - paper_value("/table1_LIOM/uncertainty_pct/K")},
      {100.0 * (liom.uncertainty.at("T") - liom.uncertainty.at("K"))}, "points of Δp"));

  // Table 2.
  claims.push_back(difference_claim("table2", "LFOM beats LIOM (Nrmse)", lfom.spec.experiments,
                                    gain(lfom, liom, true), gain(lfom, liom, false)));
  claims.push_back(range_claim("table2", "The LFOM order is clearly fractional", "λ ≤ 0.9",
                               lfom.spec.experiments, column(lfom, "lambda", true),
                               column(lfom, "lambda", false), 0.0, 0.9));
  {
    std::vector<double> p, h;
    for (std::size_t j = 0; j < lfom.spec.experiments.size(); ++j) {
      const auto& op = lfom.spec.experiments[j];
      p.push_back(paper_value("/table2_LFOM/nominal/nrmse/" + op) - paper_value("/table1_LIOM/nominal/nrmse/" + op));
      h.push_back(lfom.nominal.nrmse[j] - liom.nominal.nrmse[index_of(liom.spec.experiments, op)]);
    }
    claims.push_back(difference_claim("table2", "The nominal LFOM beats the nominal LIOM (Nrmse)",
                                      lfom.spec.experiments, p, h));
  }

  // Tables 3 and 4.
  claims.push_back(difference_claim("table3", "NLIOM-S beats LIOM (Nrmse)", nliom_s.spec.experiments,
                                    gain(nliom_s, liom, true), gain(nliom_s, liom, false)));
  claims.push_back(range_claim("table3", "The NLIOM-S exponent is near the orifice law's 1/2",
                               "0.25 ≤ γ ≤ 0.75", nliom_s.spec.experiments,
                               column(nliom_s, "gamma", true), column(nliom_s, "gamma", false), 0.25, 0.75));
  claims.push_back(difference_claim("table4", "NLFOM-S beats NLIOM-S (Nrmse)", nlfom_s.spec.experiments,
                                    gain(nlfom_s, nliom_s, true), gain(nlfom_s, nliom_s, false)));
  claims.push_back(difference_claim("table4", "NLFOM-S beats LFOM (Nrmse)", nlfom_s.spec.experiments,
                                    gain(nlfom_s, lfom, true), gain(nlfom_s, lfom, false)));
  claims.push_back(range_claim("table4", "The NLFOM-S order is clearly fractional", "λ ≤ 0.9",
                               nlfom_s.spec.experiments, column(nlfom_s, "lambda", true),
                               column(nlfom_s, "lambda", false), 0.0, 0.9));
  {
    std::vector<std::string> where;
    std::vector<double> p, h;
    for (const auto& n : parameter_names(ModelKind::nlfom_s)) {
      if (n == "L") continue;
      where.push_back("Δ" + n);
      p.push_back(paper_value("/table4_NLFOM_S/uncertainty_pct/" + n));
      h.push_back(100.0 * nlfom_s.uncertainty.at(n));
    }
    claims.push_back(range_claim("table4", "The NLFOM-S parameters vary little between op1 and op2",
                                 "Δp ≤ 15 %", where, p, h, 0.0, 15.0));
  }

  // Table 5.
  add_validation_claims(r.table5, "NLFOM-S", claims);

  // Tables 6 and 7.
  claims.push_back(difference_claim("table6", "NLIOM-F beats LIOM (Nrmse)", nliom_f.spec.experiments,
                                    gain(nliom_f, liom, true), gain(nliom_f, liom, false)));
  claims.push_back(range_claim("table6", "The free-flow exponent is large", "γ ≥ 3",
                               nliom_f.spec.experiments, column(nliom_f, "gamma", true),
                               column(nliom_f, "gamma", false), 3.0, 1e300));
  claims.push_back(difference_claim("table7", "NLFOM-F beats NLIOM-F (Nrmse)", nlfom_f.spec.experiments,
                                    gain(nlfom_f, nliom_f, true), gain(nlfom_f, nliom_f, false)));
  claims.push_back(difference_claim(
      "table7", "The nominal γ is higher in free flow than in submerged flow (NLFOM-F − NLFOM-S)",
      {"the nominal models"},
      {paper_value("/table7_NLFOM_F/nominal/gamma") - paper_value("/table4_NLFOM_S/nominal/gamma")},
      {nlfom_f.nominal.model.p.gamma - nlfom_s.nominal.model.p.gamma}, ""));
  claims.push_back(close_claim("table7", "The free-flow gains (LIOM K at op3, op4) agree with the paper's within 30 %",
                               {"op3", "op4"},
                               {paper_value("/table1_LIOM/fits/op3/K"), paper_value("/table1_LIOM/fits/op4/K")},
                               {here_parameter(liom.fits[index_of(liom.spec.experiments, "op3")].model, "K"),
                                here_parameter(liom.fits[index_of(liom.spec.experiments, "op4")].model, "K")},
                               0.30, true, "mm/mm"));

  // Table 8.
  add_validation_claims(r.table8, "NLFOM-F", claims);

  // Figure 6: flow regimes.
  {
    std::vector<std::string> sub_where, free_where;
    std::vector<double> sub_p, sub_h, free_p, free_h;
    for (const auto& reg : r.regimes) {
      const bool is_sub = std::find(nliom_s.spec.experiments.begin(), nliom_s.spec.experiments.end(),
                                    reg.experiment) != nliom_s.spec.experiments.end();
      const bool is_free = std::find(nliom_f.spec.experiments.begin(), nliom_f.spec.experiments.end(),
                                     reg.experiment) != nliom_f.spec.experiments.end();
      if (is_sub) {
        sub_where.push_back(reg.experiment);
        sub_p.push_back(0.0);
        sub_h.push_back(100.0 * reg.free_fraction);
      } else if (is_free) {
        free_where.push_back(reg.experiment);
        free_p.push_back(100.0);
        free_h.push_back(100.0 * reg.free_fraction);
      }
    }
    claims.push_back(range_claim("figure6", "The submerged-flow experiments stay submerged (share of free-flow samples, %)",
                                 "0 %", sub_where, sub_p, sub_h, 0.0, 0.0));
    claims.push_back(range_claim("figure6", "The free-flow experiments stay free (share of free-flow samples, %)",
                                 "100 %", free_where, free_p, free_h, 100.0, 100.0));
  }
  // Figure 4: PRBS bandwidth.
  claims.push_back(close_claim("figure4", "The PRBS −3 dB bandwidth agrees with the paper's 5.58 rad/s within 5 %",
                               {r.spectrum.experiment}, {5.58}, {r.spectrum.bandwidth_measured_rad_s}, 0.05,
                               true, "rad/s"));
  return claims;
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
  if (const auto why = options.validate(); !why.empty()) throw InputError(why);
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
  for (const auto& spec : specs) r.tables.push_back(build_model_table(spec, data, options));
  if (options.progress) options.progress("validation and figures");
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
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

// ---------------------------------------------------------------------------------------------
// Outputs.

namespace {

nlohmann::json parameters_json(const Model& m) {
  nlohmann::json p;
  for (const auto& n : parameter_names(m.kind)) p[n] = here_parameter(m, n);
  if (uses_upstream_level(m.kind)) {
    p["K_at_head_ref"] = m.p.K;
    p["head_ref_mm"] = m.p.head_ref_mm;
  }
  return p;
}

// Paper parameter (nullopt when the JSON has no such number).
std::optional<double> paper_opt(const std::string& pointer) {
  const auto& t = paper_tables();
  const nlohmann::json::json_pointer p(pointer);
  if (!t.contains(p) || !t.at(p).is_number()) return std::nullopt;
  return t.at(p).get<double>();
}

std::string cell(std::optional<double> v, int digits) { return v ? fmt(*v, digits) : "–"; }

int digits_for(const std::string& name) {
  if (name == "nrmse" || name == "L") return 2;
  if (name == "lambda" || name == "gamma") return 2;
  return 4;
}

std::string display_name(const std::string& n) {
  if (n == "lambda") return "λ";
  if (n == "gamma") return "γ";
  if (n == "nrmse") return "Nrmse %";
  return n;
}

}  // namespace

nlohmann::json to_json(const StudyResult& r) {
  nlohmann::json out;
  out["study"] = "Gharab, Feliu-Batlle & Rivas-Perez (2019), Tables 1-8, on recordings of the simulated "
                 "laboratory canal";
  out["units"] = "K in mm/mm (nonlinear models: the paper's K / H^gamma, levels in mm), T and L in s, "
                 "Nrmse in % (eq. 19), IAE in mm s (eq. 20), uncertainty index in % (eq. 22)";
  out["gamma_grid"] = {r.gamma.first, r.gamma.last, r.gamma.step};
  out["seconds"] = r.seconds;
  for (const auto& t : r.tables) {
    nlohmann::json j;
    j["title"] = t.spec.title;
    j["model"] = model_name(t.spec.kind);
    for (std::size_t k = 0; k < t.spec.experiments.size(); ++k) {
      const auto& op = t.spec.experiments[k];
      nlohmann::json row;
      row["here"] = parameters_json(t.fits[k].model);
      row["here"]["nrmse"] = t.fits[k].nrmse.front();
      row["here"]["iae"] = t.fits[k].iae.front();
      row["paper"] = paper_tables().at(t.spec.paper_key).at("fits").at(op);
      j["fits"][op] = row;
    }
    j["nominal"]["here"] = parameters_json(t.nominal.model);
    j["nominal"]["here"]["iae_c"] = t.nominal.iae_total;
    for (std::size_t k = 0; k < t.spec.experiments.size(); ++k) {
      j["nominal"]["here"]["nrmse"][t.spec.experiments[k]] = t.nominal.nrmse[k];
    }
    j["nominal"]["paper"] = paper_tables().at(t.spec.paper_key).at("nominal");
    for (const auto& [n, v] : t.uncertainty) j["uncertainty_pct"]["here"][n] = 100.0 * v;
    j["uncertainty_pct"]["paper"] = paper_tables().at(t.spec.paper_key).at("uncertainty_pct");
    if (!t.sweeps.empty()) {
      for (std::size_t k = 0; k < t.sweeps.size(); ++k) {
        j["gamma_sweep"][t.spec.experiments[k]] = {{"gamma", t.sweeps[k].gamma}, {"nrmse", t.sweeps[k].nrmse}};
      }
      j["gamma_sweep"]["nominal"] = {{"gamma", t.nominal_sweep->gamma}, {"nrmse", t.nominal_sweep->nrmse}};
    }
    out["tables"][t.spec.id] = j;
  }
  for (const auto* v : {&r.table5, &r.table8}) {
    nlohmann::json j;
    j["title"] = v->title;
    for (std::size_t row = 0; row < v->experiments.size(); ++row) {
      nlohmann::json e;
      e["paper_experiment"] = v->paper_experiments[row];
      for (std::size_t m = 0; m < v->models.size(); ++m) {
        e["here"][v->models[m]] = v->results[row][m].nrmse;
        e["paper"][v->models[m]] = paper_opt("/" + v->paper_key + "/" + v->paper_experiments[row] + "/" +
                                             v->models[m]).value_or(NAN);
      }
      j["nrmse"][v->experiments[row]] = e;
    }
    out["tables"][v->id] = j;
  }
  for (const auto& g : r.regimes) {
    out["regimes"][g.experiment] = {{"operating_opening_mm", g.operating_opening_mm},
                                    {"free_fraction", g.free_fraction},
                                    {"min_margin_mm", g.min_margin_mm},
                                    {"max_margin_mm", g.max_margin_mm}};
  }
  out["prbs_spectrum"] = {{"experiment", r.spectrum.experiment},
                          {"bandwidth_design_rad_s", r.spectrum.bandwidth_design_rad_s},
                          {"bandwidth_measured_rad_s", r.spectrum.bandwidth_measured_rad_s},
                          {"bandwidth_paper_rad_s", 5.58}};
  nlohmann::json claims = nlohmann::json::array();
  for (const auto& c : r.claims) claims.push_back({{"table", c.table}, {"holds", c.holds}, {"text", c.text}});
  out["conclusions"] = claims;
  return out;
}

std::string to_markdown(const StudyResult& r) {
  std::ostringstream md;
  std::size_t holds = 0;
  for (const auto& c : r.claims) holds += c.holds ? 1 : 0;
  md << "# The paper's study on the simulated laboratory canal\n\n"
     << "Gharab, Feliu-Batlle & Rivas-Perez (2019), Tables 1–8, repeated on recordings of canalsim's "
        "laboratory canal (builtin scenario `lab`). Each cell shows the paper's value, then ours "
        "(paper / here). K in mm/mm (nonlinear models: the paper's scale K / H^γ), T and L in s, "
        "Nrmse in % (eq. 19), Δp in % (eq. 22). γ grid "
     << fmt(r.gamma.first, 2) << ":" << fmt(r.gamma.last, 2) << ":" << fmt(r.gamma.step, 2)
     << ". Of the paper's conclusions checked, " << holds << " of " << r.claims.size()
     << " hold here.\n\n";
  const auto claims_of = [&](const std::string& id) {
    for (const auto& c : r.claims) {
      if (c.table == id) md << "- " << (c.holds ? "**holds** " : "**does not hold** ") << c.text << "\n";
    }
    md << "\n";
  };
  int number = 0;
  for (const auto& t : r.tables) {
    number = std::stoi(t.spec.id.substr(5));
    const auto names = parameter_names(t.spec.kind);
    md << "## Table " << number << " — " << t.spec.title << "\n\n| |";
    for (const auto& n : names) md << " " << display_name(n) << " |";
    md << " Nrmse % |\n|---|";
    for (std::size_t i = 0; i <= names.size(); ++i) md << "---|";
    md << "\n";
    for (std::size_t k = 0; k < t.spec.experiments.size(); ++k) {
      const auto& op = t.spec.experiments[k];
      md << "| " << op << " |";
      for (const auto& n : names) {
        md << " " << cell(paper_opt(paper_fit(t, op, n)), digits_for(n)) << " / "
           << parameter_fmt(here_parameter(t.fits[k].model, n), digits_for(n)) << " |";
      }
      md << " " << cell(paper_opt(paper_fit(t, op, "nrmse")), 2) << " / " << fmt(t.fits[k].nrmse.front(), 2)
         << " |\n";
    }
    for (std::size_t k = 0; k < t.spec.experiments.size(); ++k) {
      const auto& op = t.spec.experiments[k];
      md << "| nominal @ " << op << " |";
      for (const auto& n : names) {
        md << " " << cell(paper_opt("/" + t.spec.paper_key + "/nominal/" + n), digits_for(n)) << " / "
           << parameter_fmt(here_parameter(t.nominal.model, n), digits_for(n)) << " |";
      }
      md << " " << cell(paper_opt("/" + t.spec.paper_key + "/nominal/nrmse/" + op), 2) << " / "
         << fmt(t.nominal.nrmse[k], 2) << " |\n";
    }
    md << "| Δp % |";
    for (const auto& n : names) {
      md << " " << cell(paper_opt("/" + t.spec.paper_key + "/uncertainty_pct/" + n), 2) << " / "
         << uncertainty_cell(t.uncertainty.at(n)) << " |";
    }
    md << " |\n\n";
    if (t.spec.kind == ModelKind::nlfom_s) {
      // Table 5 follows Table 4.
      const auto& v = r.table5;
      md << "## Table 5 — " << v.title << "\n\n| here (paper) |";
      for (const auto& m : v.models) md << " " << m << " |";
      md << "\n|---|";
      for (std::size_t i = 0; i < v.models.size(); ++i) md << "---|";
      md << "\n";
      for (std::size_t row = 0; row < v.experiments.size(); ++row) {
        md << "| " << v.experiments[row] << " (" << v.paper_experiments[row] << ") |";
        for (std::size_t m = 0; m < v.models.size(); ++m) {
          md << " " << cell(paper_opt("/" + v.paper_key + "/" + v.paper_experiments[row] + "/" + v.models[m]), 2)
             << " / " << fmt(v.results[row][m].nrmse, 2) << " |";
        }
        md << "\n";
      }
      md << "\n";
    }
  }
  {
    const auto& v = r.table8;
    md << "## Table 8 — " << v.title << "\n\nOur op3b/op4b repeat op3/op4 (43 and 45 mm) with another PRBS "
          "seed and sensor noise, as the paper's op3*/op4* repeat them.\n\n| here (paper) |";
    for (const auto& m : v.models) md << " " << m << " |";
    md << "\n|---|";
    for (std::size_t i = 0; i < v.models.size(); ++i) md << "---|";
    md << "\n";
    for (std::size_t row = 0; row < v.experiments.size(); ++row) {
      md << "| " << v.experiments[row] << " (" << v.paper_experiments[row] << ") |";
      for (std::size_t m = 0; m < v.models.size(); ++m) {
        md << " " << cell(paper_opt("/" + v.paper_key + "/" + v.paper_experiments[row] + "/" + v.models[m]), 2)
           << " / " << fmt(v.results[row][m].nrmse, 2) << " |";
      }
      md << "\n";
    }
    md << "\n";
  }
  md << "## Conclusions\n\n";
  for (const std::string id : {"table1", "table2", "table3", "table4", "table5", "table6", "table7", "table8"}) {
    md << "### Table " << id.substr(5) << "\n\n";
    claims_of(id);
  }
  md << "### Flow regimes (Figure 6)\n\n| experiment | opening mm | free-flow samples % | min y_up − y_lc mm | max y_up − y_lc mm |\n|---|---|---|---|---|\n";
  for (const auto& g : r.regimes) {
    md << "| " << g.experiment << " | " << fmt(g.operating_opening_mm, 1) << " | " << fmt(100.0 * g.free_fraction, 1)
       << " | " << fmt(g.min_margin_mm, 2) << " | " << fmt(g.max_margin_mm, 2) << " |\n";
  }
  md << "\n";
  claims_of("figure6");
  md << "### PRBS spectrum (Figure 4)\n\nDesign half-power bandwidth " << fmt(r.spectrum.bandwidth_design_rad_s, 3)
     << " rad/s; measured on the " << r.spectrum.experiment << " command "
     << fmt(r.spectrum.bandwidth_measured_rad_s, 3) << " rad/s; paper 5.58 rad/s.\n\n";
  claims_of("figure4");
  md << "Run time of the study (fits, sweeps, validation): " << fmt(r.seconds, 1) << " s.\n";
  return md.str();
}

namespace {

// Every k-th sample so that at most `points` remain (0 = all).
std::vector<double> thin(const std::vector<double>& v, std::size_t points, int digits = 3) {
  const std::size_t step = (points == 0 || v.size() <= points) ? 1 : (v.size() + points - 1) / points;
  std::vector<double> out;
  const double scale = std::pow(10.0, digits);
  for (std::size_t i = 0; i < v.size(); i += step) out.push_back(std::round(v[i] * scale) / scale);
  return out;
}

const char* kHtmlHead = R"html(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>canalsim reproduce — the paper's study on the simulated laboratory canal</title>
<style>
body{font-family:system-ui,sans-serif;max-width:1100px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:90%}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
th{background:#f3f3f3} td:first-child{text-align:left}
.holds{color:#17692b}.fails{color:#a3141c}
.plot{margin:.5em 0 1.5em} .plot svg{background:#fff;border:1px solid #ddd}
.legend span{margin-right:1em;font-size:85%}
small{color:#666}
</style></head><body>
)html";

// Plotting code: chart(id, spec) draws line series (x, y arrays) as inline SVG.
const char* kHtmlScript = R"js(
function niceTicks(lo, hi, n) {
  const span = hi - lo || 1, raw = span / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map(m => m * mag).find(s => span / s <= n) || 10 * mag;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) out.push(+v.toPrecision(12));
  return out;
}
function chart(id, spec) {
  const W = 1000, H = spec.height || 300, m = {l: 60, r: 15, t: 24, b: 40};
  const ns = 'http://www.w3.org/2000/svg';
  const fx = spec.logx ? Math.log10 : (v => v), fy = spec.logy ? Math.log10 : (v => v);
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const s of spec.series) for (let i = 0; i < s.x.length; i++) {
    const X = fx(s.x[i]), Y = fy(s.y[i]);
    if (!isFinite(X) || !isFinite(Y)) continue;
    x0 = Math.min(x0, X); x1 = Math.max(x1, X); y0 = Math.min(y0, Y); y1 = Math.max(y1, Y);
  }
  if (spec.ymin !== undefined) y0 = Math.max(y0, spec.ymin);
  const pad = (y1 - y0) * 0.05 || 1; y0 -= pad; y1 += pad;
  const sx = v => m.l + (fx(v) - x0) / (x1 - x0 || 1) * (W - m.l - m.r);
  const sy = v => H - m.b - (Math.max(fy(v), y0) - y0) / (y1 - y0) * (H - m.t - m.b);
  const svg = document.createElementNS(ns, 'svg');
  svg.setAttribute('viewBox', `0 0 ${W} ${H}`); svg.setAttribute('width', '100%');
  const el = (tag, attrs, text) => { const e = document.createElementNS(ns, tag);
    for (const k in attrs) e.setAttribute(k, attrs[k]); if (text !== undefined) e.textContent = text;
    svg.appendChild(e); return e; };
  const xt = spec.logx ? [] : niceTicks(x0, x1, 10), yt = spec.logy ? [] : niceTicks(y0, y1, 6);
  if (spec.logx) for (let e = Math.floor(x0); e <= Math.ceil(x1); e++) xt.push(Math.pow(10, e));
  if (spec.logy) for (let e = Math.floor(y0); e <= Math.ceil(y1); e++) yt.push(Math.pow(10, e));
  for (const v of xt) { const X = sx(v); if (X < m.l - 1 || X > W - m.r + 1) continue;
    el('line', {x1: X, x2: X, y1: m.t, y2: H - m.b, stroke: '#eee'});
    el('text', {x: X, y: H - m.b + 14, 'font-size': 11, 'text-anchor': 'middle'}, +v.toPrecision(4)); }
  for (const v of yt) { const Y = sy(v); if (Y < m.t - 1 || Y > H - m.b + 1) continue;
    el('line', {x1: m.l, x2: W - m.r, y1: Y, y2: Y, stroke: '#eee'});
    el('text', {x: m.l - 4, y: Y + 4, 'font-size': 11, 'text-anchor': 'end'}, +v.toPrecision(4)); }
  el('rect', {x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b, fill: 'none', stroke: '#999'});
  el('text', {x: W / 2, y: H - 6, 'font-size': 12, 'text-anchor': 'middle'}, spec.xlabel || '');
  el('text', {x: 12, y: H / 2, 'font-size': 12, 'text-anchor': 'middle',
              transform: `rotate(-90 12 ${H / 2})`}, spec.ylabel || '');
  el('text', {x: m.l, y: 15, 'font-size': 13, 'font-weight': 'bold'}, spec.title || '');
  const colors = ['#222', '#d62728', '#1f77b4', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b'];
  spec.series.forEach((s, k) => {
    const c = s.color || colors[k % colors.length];
    if (s.stem) { for (let i = 0; i < s.x.length; i++) el('line', {x1: sx(s.x[i]), x2: sx(s.x[i]),
        y1: sy(s.y[i]), y2: H - m.b, stroke: c, 'stroke-width': 0.6}); return; }
    let d = '';
    for (let i = 0; i < s.x.length; i++) { if (!isFinite(fy(s.y[i]))) continue;
      d += (d ? 'L' : 'M') + sx(s.x[i]).toFixed(1) + ' ' + sy(s.y[i]).toFixed(1); }
    el('path', {d, fill: 'none', stroke: c, 'stroke-width': s.width || 1.2,
                'stroke-dasharray': s.dash || ''});
    if (s.mark !== undefined) el('circle', {cx: sx(s.x[s.mark]), cy: sy(s.y[s.mark]), r: 4, fill: c});
  });
  const box = document.getElementById(id);
  box.appendChild(svg);
  const legend = document.createElement('div'); legend.className = 'legend';
  spec.series.forEach((s, k) => { const sp = document.createElement('span');
    sp.innerHTML = `<b style="color:${s.color || colors[k % colors.length]}">&#9644;</b> ${s.name}`;
    legend.appendChild(sp); });
  box.appendChild(legend);
}
function draw() {
  const D = DATA;
  let n = 0;
  const add = (section, spec) => { const div = document.createElement('div'); div.className = 'plot';
    div.id = 'plot' + (n++); document.getElementById(section).appendChild(div); chart(div.id, spec); };
  for (const r of D.responses) add('responses', {title: r.title, xlabel: 't (s)', ylabel: 'y_dwe (mm)',
      series: r.series});
  for (const g of D.gamma) add('gamma', {title: g.title, xlabel: 'γ', ylabel: 'Nrmse (%)', series: g.series,
      ymin: g.ymin, height: 260});
  for (const f of D.regimes) add('regimes', {title: f.title, xlabel: 't (s)', ylabel: 'level (mm)',
      series: f.series, height: 260});
  const s = D.spectrum;
  add('spectrum', {title: 'Magnitude of the Fourier transform of a unit-amplitude PRBS and of a unit step',
      xlabel: 'ω (rad/s)', ylabel: '|F(ω)|', logy: true, height: 320, series: [
      {name: 'PRBS lines (recorded command)', x: s.omega, y: s.magnitude, stem: true, color: '#1f77b4'},
      {name: 'envelope Tc √(N+1) |sinc|', x: s.omega, y: s.envelope, color: '#222'},
      {name: 'unit step 1/ω', x: s.omega, y: s.step, color: '#d62728'},
      {name: 'envelope max/√2 (−3 dB)', x: [s.omega[0], s.omega[s.omega.length - 1]],
       y: [s.peak / Math.SQRT2, s.peak / Math.SQRT2], dash: '4 3', color: '#2ca02c'}]});
}
draw();
)js";

std::string escape_html(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      default: out += c;
    }
  }
  return out;
}

// Markdown table lines (| a | b |) to an HTML table, other lines to paragraphs/lists/headings.
std::string markdown_to_html(const std::string& md) {
  std::istringstream in(md);
  std::ostringstream out;
  std::string line;
  bool in_table = false, header = false, in_list = false;
  const auto inline_md = [](std::string s) {
    s = escape_html(s);
    for (const std::string mark : {"**", "`"}) {
      bool open = true;
      for (auto p = s.find(mark); p != std::string::npos; p = s.find(mark, p)) {
        const std::string tag = mark == "**" ? (open ? "<b>" : "</b>") : (open ? "<code>" : "</code>");
        s.replace(p, mark.size(), tag);
        open = !open;
      }
    }
    return s;
  };
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '|') {
      if (!in_table) {
        out << "<table>\n";
        in_table = true;
        header = true;
      }
      if (line.rfind("|---", 0) == 0) continue;
      std::vector<std::string> cells;
      std::size_t p = 1;
      while (p < line.size()) {
        const auto q = line.find('|', p);
        if (q == std::string::npos) break;
        auto c = line.substr(p, q - p);
        const auto a = c.find_first_not_of(' '), b = c.find_last_not_of(' ');
        cells.push_back(a == std::string::npos ? "" : c.substr(a, b - a + 1));
        p = q + 1;
      }
      out << "<tr>";
      for (const auto& c : cells) out << (header ? "<th>" : "<td>") << inline_md(c) << (header ? "</th>" : "</td>");
      out << "</tr>\n";
      header = false;
      continue;
    }
    if (in_table) {
      out << "</table>\n";
      in_table = false;
    }
    if (line.rfind("- ", 0) == 0) {
      if (!in_list) out << "<ul>\n";
      in_list = true;
      const bool holds = line.find("**holds**") != std::string::npos;
      out << "<li class=\"" << (holds ? "holds" : "fails") << "\">" << inline_md(line.substr(2)) << "</li>\n";
      continue;
    }
    if (in_list) {
      out << "</ul>\n";
      in_list = false;
    }
    if (line.empty()) continue;
    if (line.rfind("### ", 0) == 0) {
      out << "<h3>" << inline_md(line.substr(4)) << "</h3>\n";
    } else if (line.rfind("## ", 0) == 0) {
      out << "<h2>" << inline_md(line.substr(3)) << "</h2>\n";
    } else if (line.rfind("# ", 0) == 0) {
      out << "<h1>" << inline_md(line.substr(2)) << "</h1>\n";
    } else {
      out << "<p>" << inline_md(line) << "</p>\n";
    }
  }
  if (in_table) out << "</table>\n";
  if (in_list) out << "</ul>\n";
  return out.str();
}

nlohmann::json series(const std::string& name, const std::vector<double>& x, const std::vector<double>& y,
                      std::size_t points, const std::string& color = "") {
  nlohmann::json s = {{"name", name}, {"x", thin(x, points, 3)}, {"y", thin(y, points, 3)}};
  if (!color.empty()) s["color"] = color;
  return s;
}

}  // namespace

std::string to_html(const StudyResult& r, const std::map<std::string, Recording>& recordings,
                    const StudyOptions& options) {
  const std::size_t points = options.plot_points;
  nlohmann::json data;
  // Recorded vs model responses: fitted models at op1–op4, nominal models at the validation points.
  data["responses"] = nlohmann::json::array();
  std::vector<std::string> fit_ops;
  for (const auto& t : r.tables) {
    for (const auto& op : t.spec.experiments) {
      if (std::find(fit_ops.begin(), fit_ops.end(), op) == fit_ops.end()) fit_ops.push_back(op);
    }
  }
  for (const auto& op : fit_ops) {
    const auto& rec = recordings.at(op);
    const auto& t_s = rec.column(columns::time);
    nlohmann::json plot;
    plot["title"] = "Recorded and fitted responses at " + op + " (" + rec.meta("operating_opening_mm", "?") +
                    " mm)";
    plot["series"].push_back(series("recorded y_dwe", t_s, rec.column(columns::level_downstream_end), points, "#222"));
    for (const auto& t : r.tables) {
      const auto it = std::find(t.spec.experiments.begin(), t.spec.experiments.end(), op);
      if (it == t.spec.experiments.end()) continue;
      const auto k = static_cast<std::size_t>(it - t.spec.experiments.begin());
      plot["series"].push_back(series(upper_name(t.spec.kind) + " (Nrmse " + fmt(t.fits[k].nrmse.front(), 1) + " %)",
                                      t_s, t.fits[k].response.front(), points));
    }
    data["responses"].push_back(plot);
  }
  for (const auto* v : {&r.table5, &r.table8}) {
    for (std::size_t row = 0; row < v->experiments.size(); ++row) {
      const auto& op = v->experiments[row];
      const auto& rec = recordings.at(op);
      const auto& t_s = rec.column(columns::time);
      nlohmann::json plot;
      plot["title"] = "Validation of the nominal models at " + op + " (paper " + v->paper_experiments[row] + ", " +
                      rec.meta("operating_opening_mm", "?") + " mm)";
      plot["series"].push_back(series("recorded y_dwe", t_s, rec.column(columns::level_downstream_end), points, "#222"));
      for (std::size_t m = 0; m < v->models.size(); ++m) {
        plot["series"].push_back(series(v->models[m] + " nominal (Nrmse " + fmt(v->results[row][m].nrmse, 1) + " %)",
                                        t_s, v->results[row][m].response, points));
      }
      data["responses"].push_back(plot);
    }
  }
  // Nrmse against γ (Figures 8 and 10).
  data["gamma"] = nlohmann::json::array();
  for (const auto& t : r.tables) {
    if (t.sweeps.empty()) continue;
    nlohmann::json g;
    g["title"] = "Nrmse against γ, " + upper_name(t.spec.kind) + " (dots: best γ)";
    double ymin = 1e300;
    for (std::size_t k = 0; k < t.sweeps.size(); ++k) {
      auto s = series(t.spec.experiments[k] + " (best γ " + fmt(t.sweeps[k].gamma[t.sweeps[k].best], 2) + ")",
                      t.sweeps[k].gamma, t.sweeps[k].nrmse, 0);
      s["mark"] = t.sweeps[k].best;
      g["series"].push_back(s);
      ymin = std::min(ymin, t.sweeps[k].nrmse[t.sweeps[k].best]);
    }
    auto s = series("nominal (best γ " + fmt(t.nominal_sweep->gamma[t.nominal_sweep->best], 2) + ")",
                    t.nominal_sweep->gamma, t.nominal_sweep->nrmse, 0);
    s["mark"] = t.nominal_sweep->best;
    s["dash"] = "5 3";
    g["series"].push_back(s);
    g["ymin"] = ymin - 40.0;  // keep the interesting part visible when low γ fits collapse
    data["gamma"].push_back(g);
  }
  // Flow regimes (Figure 6).
  data["regimes"] = nlohmann::json::array();
  for (const auto& reg : r.regimes) {
    const auto& rec = recordings.at(reg.experiment);
    if (!rec.has(columns::upstream_level) || !rec.has(columns::gate_position)) continue;
    const auto& t_s = rec.column(columns::time);
    const auto& y_dwe = rec.column(columns::level_downstream_end);
    const auto& x_up = rec.column(columns::gate_position);
    std::vector<double> y_lc(rec.size());
    for (std::size_t k = 0; k < rec.size(); ++k) y_lc[k] = free_flow_limit_mm(y_dwe[k], x_up[k]);
    nlohmann::json f;
    f["title"] = "Flow condition at " + reg.experiment + " (" + fmt(reg.operating_opening_mm, 0) +
                 " mm): free flow on " + fmt(100.0 * reg.free_fraction, 1) + " % of the samples";
    f["series"].push_back(series("y_up", t_s, rec.column(columns::upstream_level), points, "#1f77b4"));
    f["series"].push_back(series("y_lc (eq. 23)", t_s, y_lc, points, "#d62728"));
    f["series"].push_back(series("y_dwe", t_s, y_dwe, points, "#222"));
    data["regimes"].push_back(f);
  }
  double peak = 0.0;
  for (double v : r.spectrum.envelope) peak = std::max(peak, v);
  data["spectrum"] = {{"omega", thin(r.spectrum.omega, 0, 4)},
                      {"magnitude", thin(r.spectrum.magnitude, 0, 4)},
                      {"envelope", thin(r.spectrum.envelope, 0, 4)},
                      {"step", thin(r.spectrum.step, 0, 4)},
                      {"peak", peak}};

  std::ostringstream html;
  html << kHtmlHead << markdown_to_html(to_markdown(r))
       << "<h2>Recorded and model responses</h2><div id=\"responses\"></div>\n"
       << "<h2>Nrmse against γ (Figures 8 and 10)</h2><div id=\"gamma\"></div>\n"
       << "<h2>Flow regimes (Figure 6): y_up, y_lc = 0.81 y_dwe (y_dwe/x_up)^0.72, y_dwe</h2>"
          "<p><small>Free flow where y_up &gt; y_lc (condition 8), submerged where y_up &lt; y_lc "
          "(condition 10).</small></p><div id=\"regimes\"></div>\n"
       << "<h2>PRBS spectrum (Figure 4)</h2><p><small>Design half-power bandwidth "
       << fmt(r.spectrum.bandwidth_design_rad_s, 3) << " rad/s, measured " << fmt(r.spectrum.bandwidth_measured_rad_s, 3)
       << " rad/s, paper 5.58 rad/s.</small></p><div id=\"spectrum\"></div>\n"
       << "<script>\nconst DATA = ";
  std::string json = data.dump();
  // Keep "</script>" out of the inline data.
  for (std::size_t p = json.find("</"); p != std::string::npos; p = json.find("</", p + 2)) json.replace(p, 2, "<\\/");
  html << json << ";\n" << kHtmlScript << "</script>\n</body></html>\n";
  return html.str();
}

}  // namespace canalsim::reduced::study
