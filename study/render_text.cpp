// tables.json and tables.md.
#include "study/render.hpp"

#include <cmath>
#include <optional>
#include <sstream>

#include "study/paper.hpp"
#include "study/text.hpp"

namespace canalsim::study {

using namespace canalsim::reduced;

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

std::string cell(std::optional<double> v, int digits) { return v ? format_fixed(*v, digits) : "–"; }

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
  for (const auto& c : r.claims) {
    claims.push_back({{"table", c.table}, {"holds", c.holds}, {"text", c.text}, {"why", c.why}});
  }
  out["conclusions"] = claims;
  return out;
}

namespace {

// A validation table (5 or 8) in Markdown: the paper's Nrmse / ours per experiment and model.
void validation_rows(std::ostringstream& md, const ValidationTable& v) {
  md << "| here (paper) |";
  for (const auto& m : v.models) md << " " << m << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < v.models.size(); ++i) md << "---|";
  md << "\n";
  for (std::size_t row = 0; row < v.experiments.size(); ++row) {
    md << "| " << v.experiments[row] << " (" << v.paper_experiments[row] << ") |";
    for (std::size_t m = 0; m < v.models.size(); ++m) {
      md << " " << cell(paper_opt("/" + v.paper_key + "/" + v.paper_experiments[row] + "/" + v.models[m]), 2)
         << " / " << format_fixed(v.results[row][m].nrmse, 2) << " |";
    }
    md << "\n";
  }
  md << "\n";
}

}  // namespace

std::string to_markdown(const StudyResult& r) {
  std::ostringstream md;
  std::size_t holds = 0;
  for (const auto& c : r.claims) holds += c.holds ? 1 : 0;
  md << "# The paper's study on the simulated laboratory canal\n\n"
     << "Gharab, Feliu-Batlle & Rivas-Perez (2019), Tables 1–8, repeated on recordings of canalsim's "
        "laboratory canal (builtin scenario `lab`). Each cell shows the paper's value, then ours "
        "(paper / here). K in mm/mm (nonlinear models: the paper's scale K / H^γ), T and L in s, "
        "Nrmse in % (eq. 19), Δp in % (eq. 22). γ grid "
     << format_fixed(r.gamma.first, 2) << ":" << format_fixed(r.gamma.last, 2) << ":" << format_fixed(r.gamma.step, 2)
     << ". Of the paper's conclusions checked, " << holds << " of " << r.claims.size()
     << " hold here.\n\n";
  const auto claims_of = [&](const std::string& id) {
    for (const auto& c : r.claims) {
      if (c.table != id) continue;
      md << "- " << (c.holds ? "**holds** " : "**does not hold** ") << c.text;
      if (!c.why.empty()) md << " *Why:* " << c.why;
      md << "\n";
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
      md << " " << cell(paper_opt(paper_fit(t, op, "nrmse")), 2) << " / " << format_fixed(t.fits[k].nrmse.front(), 2)
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
         << format_fixed(t.nominal.nrmse[k], 2) << " |\n";
    }
    md << "| Δp % |";
    for (const auto& n : names) {
      md << " " << cell(paper_opt("/" + t.spec.paper_key + "/uncertainty_pct/" + n), 2) << " / "
         << uncertainty_cell(t.uncertainty.at(n)) << " |";
    }
    md << " |\n\n";
    if (t.spec.kind == ModelKind::nlfom_s) {
      // Table 5 follows Table 4.
      md << "## Table 5 — " << r.table5.title << "\n\n";
      validation_rows(md, r.table5);
    }
  }
  {
    md << "## Table 8 — " << r.table8.title << "\n\nOur op3b/op4b repeat op3/op4 (43 and 45 mm) with another PRBS "
          "seed and sensor noise, as the paper's op3*/op4* repeat them.\n\n";
    validation_rows(md, r.table8);
  }
  md << "## Conclusions\n\n";
  for (const std::string id : {"table1", "table2", "table3", "table4", "table5", "table6", "table7", "table8"}) {
    md << "### Table " << id.substr(5) << "\n\n";
    claims_of(id);
  }
  md << "### Flow regimes (Figure 6)\n\n| experiment | opening mm | free-flow samples % | min y_up − y_lc mm | max y_up − y_lc mm |\n|---|---|---|---|---|\n";
  for (const auto& g : r.regimes) {
    md << "| " << g.experiment << " | " << format_fixed(g.operating_opening_mm, 1) << " | " << format_fixed(100.0 * g.free_fraction, 1)
       << " | " << format_fixed(g.min_margin_mm, 2) << " | " << format_fixed(g.max_margin_mm, 2) << " |\n";
  }
  md << "\n";
  claims_of("figure6");
  md << "### PRBS spectrum (Figure 4)\n\nDesign half-power bandwidth " << format_fixed(r.spectrum.bandwidth_design_rad_s, 3)
     << " rad/s; measured on the " << r.spectrum.experiment << " command "
     << format_fixed(r.spectrum.bandwidth_measured_rad_s, 3) << " rad/s; paper 5.58 rad/s.\n\n";
  claims_of("figure4");
  md << "Run time of the study (fits, sweeps, validation): " << format_fixed(r.seconds, 1) << " s.\n";
  return md.str();
}

}  // namespace canalsim::study
