#include "study/claims.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "study/paper.hpp"
#include "study/study.hpp"
#include "study/text.hpp"

namespace canalsim::study {

using namespace canalsim::reduced;

namespace {

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
    p.push_back(show_sign ? signed_fmt(paper[i], 2) : format_fixed(paper[i], 2));
    h.push_back(show_sign ? signed_fmt(here[i], 2) : format_fixed(here[i], 2));
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

namespace {

// A table's per-op column of a parameter (or "nrmse"): the paper's, or here.
std::vector<double> column(const ModelTable& t, const std::string& name, bool paper) {
  std::vector<double> out;
  for (std::size_t j = 0; j < t.spec.experiments.size(); ++j) {
    out.push_back(paper ? paper_value(paper_fit(t, t.spec.experiments[j], name))
                        : (name == "nrmse" ? t.fits[j].nrmse.front() : here_parameter(t.fits[j].model, name)));
  }
  return out;
}

// Nrmse gain of table a over table b at a's ops.
std::vector<double> gain(const ModelTable& a, const ModelTable& b, bool paper) {
  std::vector<double> out;
  for (const auto& op : a.spec.experiments) {
    out.push_back(paper ? paper_value(paper_fit(a, op, "nrmse")) - paper_value(paper_fit(b, op, "nrmse"))
                        : here_nrmse(a, op) - here_nrmse(b, op));
  }
  return out;
}

// What the nominal model loses against the individual fits, per op (Nrmse points).
std::vector<double> nominal_loss(const ModelTable& t, bool paper) {
  std::vector<double> out;
  for (std::size_t j = 0; j < t.spec.experiments.size(); ++j) {
    const auto& op = t.spec.experiments[j];
    out.push_back(paper ? paper_value(paper_fit(t, op, "nrmse")) - paper_value("/" + t.spec.paper_key + "/nominal/nrmse/" + op)
                        : t.fits[j].nrmse.front() - t.nominal.nrmse[j]);
  }
  return out;
}

// Table 1: the LIOM's parameters and fit, and how much they vary.
void add_liom_claims(const ModelTable& liom, std::vector<Claim>& claims) {
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
}

// Table 2: LFOM against LIOM.
void add_lfom_claims(const ModelTable& lfom, const ModelTable& liom, std::vector<Claim>& claims) {
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
}

// Tables 3 and 4: the submerged-flow nonlinear models.
void add_submerged_flow_claims(const ModelTable& nliom_s, const ModelTable& nlfom_s, const ModelTable& liom,
                               const ModelTable& lfom, std::vector<Claim>& claims) {
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
}

// Tables 6 and 7: the free-flow nonlinear models.
void add_free_flow_claims(const ModelTable& nliom_f, const ModelTable& nlfom_f, const ModelTable& nlfom_s,
                          const ModelTable& liom, std::vector<Claim>& claims) {
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
}

// Figure 6 (flow regimes) and Figure 4 (the PRBS bandwidth).
void add_figure_claims(const StudyResult& r, const ModelTable& nliom_s, const ModelTable& nliom_f,
                       std::vector<Claim>& claims) {
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
}

}  // namespace

std::vector<Claim> conclusions(const StudyResult& r) {
  std::vector<Claim> claims;
  const auto& liom = find_table(r, ModelKind::liom);
  const auto& lfom = find_table(r, ModelKind::lfom);
  const auto& nliom_s = find_table(r, ModelKind::nliom_s);
  const auto& nlfom_s = find_table(r, ModelKind::nlfom_s);
  const auto& nliom_f = find_table(r, ModelKind::nliom_f);
  const auto& nlfom_f = find_table(r, ModelKind::nlfom_f);
  add_liom_claims(liom, claims);
  add_lfom_claims(lfom, liom, claims);
  add_submerged_flow_claims(nliom_s, nlfom_s, liom, lfom, claims);
  add_validation_claims(r.table5, "NLFOM-S", claims);
  add_free_flow_claims(nliom_f, nlfom_f, nlfom_s, liom, claims);
  add_validation_claims(r.table8, "NLFOM-F", claims);
  add_figure_claims(r, nliom_s, nliom_f, claims);
  return claims;
}

}  // namespace canalsim::study
