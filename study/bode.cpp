#include "study/bode.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/format.hpp"
#include "core/html.hpp"
#include "linearize/linearize.hpp"
#include "plot/composites.hpp"
#include "reduced_models/frequency.hpp"

namespace canalsim::study {
namespace {

using Complex = std::complex<double>;

const FitResult* fit_for(const StudyResult& r, ModelKind kind, const std::string& experiment) {
  for (const auto& t : r.tables) {
    if (t.spec.kind != kind) continue;
    for (std::size_t k = 0; k < t.spec.experiments.size() && k < t.fits.size(); ++k) {
      if (t.spec.experiments[k] == experiment) return &t.fits[k];
    }
  }
  return nullptr;
}

double rms_relative(const std::vector<Complex>& model, const std::vector<Complex>& truth) {
  double sum = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k) sum += std::norm(model[k] / truth[k] - 1.0);
  return std::sqrt(sum / static_cast<double>(truth.size()));
}

std::string percent(double fraction) { return format_fixed(100.0 * fraction, 1) + " %"; }

std::vector<double> gain_db(const std::vector<Complex>& g) {
  std::vector<double> out;
  for (const auto& v : g) out.push_back(20.0 * std::log10(std::abs(v)));
  return out;
}

}  // namespace

std::string fractionality_sentence(const BodeSection& b) {
  const auto& f = b.pde_fit;
  std::ostringstream s;
  s << "At " << b.experiment << " (" << format_g(b.operating_opening_mm, 3) << " mm) the linearised pool ";
  if (f.rms_relative_error > 0.10) {
    s << "is not a first-order lag of any order in the PRBS band: the LFOM fitted to its response is "
      << percent(f.rms_relative_error) << " off (λ = " << format_fixed(f.order, 2) << "; λ = 1: "
      << percent(f.integer_rms_relative_error) << ")";
  } else if (f.order < 0.9 && f.rms_relative_error <= 0.7 * f.integer_rms_relative_error) {
    s << "is fractional in the PRBS band with λ = " << format_fixed(f.order, 2) << " (LFOM fitted to its response "
      << percent(f.rms_relative_error) << " off, λ = 1: " << percent(f.integer_rms_relative_error) << ")";
  } else {
    s << "is a first-order lag in the PRBS band (λ = " << format_fixed(f.order, 2) << ", "
      << percent(f.rms_relative_error) << " off; λ = 1: " << percent(f.integer_rms_relative_error) << ")";
  }
  s << "; its gain changes by " << format_fixed(b.gain_change_db, 1) << " dB across the band. The LFOM fitted to the "
    << "recording (λ = " << format_fixed(b.fitted_lfom_lambda, 2) << ") is " << percent(b.lfom_error)
    << " from the pool's response there, the LIOM " << percent(b.liom_error) << ".";
  return s.str();
}

std::vector<BodeSection> bode_sections(const scenarios::Scenario& scenario, const StudyResult& r) {
  std::vector<BodeSection> sections;
  for (const auto& t : r.tables) {
    if (t.spec.kind != ModelKind::liom) continue;
    for (const auto& name : t.spec.experiments) {
      const FitResult* liom = fit_for(r, ModelKind::liom, name);
      const FitResult* lfom = fit_for(r, ModelKind::lfom, name);
      const auto* e = scenario.find_experiment(name);
      if (!liom || !lfom || !e || e->input.kind != scenarios::InputKind::prbs) continue;
      const linearize::FrequencyResponse pde = linearize::linearize(scenario, *e, {});
      if (!pde.band || !pde.band_fit) continue;
      BodeSection b;
      b.experiment = name;
      b.operating_opening_mm = e->operating_opening_mm;
      b.band = *pde.band;
      b.omega = linearize::log_grid({b.band.low, b.band.high, 200});
      b.pde = linearize::frequency_response(pde.system, b.omega);
      for (double w : b.omega) {
        b.liom.push_back(reduced::frequency_response(liom->model, {}, w));
        b.lfom.push_back(reduced::frequency_response(lfom->model, {}, w));
      }
      b.liom_error = rms_relative(b.liom, b.pde);
      b.lfom_error = rms_relative(b.lfom, b.pde);
      b.fitted_lfom_lambda = lfom->model.p.lambda;
      b.gain_change_db = 20.0 * std::log10(std::abs(b.pde.back()) / std::abs(b.pde.front()));
      b.pde_fit = *pde.band_fit;
      b.sentence = fractionality_sentence(b);
      sections.push_back(std::move(b));
    }
  }
  return sections;
}

nlohmann::json bode_json(const std::vector<BodeSection>& sections) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& b : sections) {
    nlohmann::json j;
    j["experiment"] = b.experiment;
    j["operating_opening_mm"] = b.operating_opening_mm;
    j["band_rad_s"] = {b.band.low, b.band.high};
    j["pde_band_lfom"] = {{"K", b.pde_fit.gain}, {"T", b.pde_fit.time}, {"lambda", b.pde_fit.order},
                          {"L_s", b.pde_fit.delay}, {"rms_relative_error", b.pde_fit.rms_relative_error},
                          {"lambda1_rms_relative_error", b.pde_fit.integer_rms_relative_error}};
    j["liom_vs_pde_rms_relative_error"] = b.liom_error;
    j["lfom_vs_pde_rms_relative_error"] = b.lfom_error;
    j["sentence"] = b.sentence;
    for (std::size_t k = 0; k < b.omega.size(); ++k) {
      j["response"].push_back({{"omega_rad_s", b.omega[k]},
                               {"pde", {b.pde[k].real(), b.pde[k].imag()}},
                               {"liom", {b.liom[k].real(), b.liom[k].imag()}},
                               {"lfom", {b.lfom[k].real(), b.lfom[k].imag()}}});
    }
    out.push_back(std::move(j));
  }
  return out;
}

std::string bode_markdown(const std::vector<BodeSection>& sections) {
  std::ostringstream md;
  md << "# Bode: the linearised pool against the fitted LIOM and LFOM\n\n"
     << "Gate → y_dwe in mm/mm over each experiment's PRBS band, the pool linearised at its steady state "
        "(`canalsim linearize`, docs/linearization.md); gain and phase (delay included) at 12 of the 200 "
        "frequencies compared.\n\n";
  for (const auto& b : sections) {
    md << "## " << b.experiment << " (" << format_g(b.operating_opening_mm, 3) << " mm), band "
       << format_g(b.band.low, 3) << "–" << format_g(b.band.high, 3) << " rad/s\n\n"
       << b.sentence << "\n\n| ω [rad/s] | PDE gain | LIOM gain | LFOM gain | PDE phase ° | LIOM phase ° | LFOM phase ° |\n"
       << "|---:|---:|---:|---:|---:|---:|---:|\n";
    // Phases unwrapped along the whole grid, then sampled.
    const auto pp = linearize::unwrapped_phase_degrees(b.pde), pi = linearize::unwrapped_phase_degrees(b.liom), pf = linearize::unwrapped_phase_degrees(b.lfom);
    for (std::size_t k = 0; k < b.omega.size(); k += std::max<std::size_t>(1, b.omega.size() / 12)) {
      md << "| " << format_g(b.omega[k], 3) << " | " << format_g(std::abs(b.pde[k]), 3) << " | "
         << format_g(std::abs(b.liom[k]), 3) << " | " << format_g(std::abs(b.lfom[k]), 3) << " | "
         << format_fixed(pp[k], 0) << " | " << format_fixed(pi[k], 0) << " | " << format_fixed(pf[k], 0) << " |\n";
    }
    md << "\n";
  }
  return md.str();
}

std::string bode_html(const std::vector<BodeSection>& sections) {
  return "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>Bode: the linearised pool and the fitted "
         "models</title></head><body style=\"font-family:sans-serif;max-width:1000px;margin:1em auto\">" +
         bode_html_section(sections, "h1", "h2") + "</body></html>\n";
}

std::vector<plot::Figure> bode_figures(const std::vector<BodeSection>& sections) {
  std::vector<plot::Figure> figures;
  for (const auto& b : sections) {
    figures.push_back(plot::bode_figure(
        "bode_" + plot::file_stem(b.experiment),
        "Gate → y_dwe at " + b.experiment + " (" + format_g(b.operating_opening_mm, 3) + " mm), over the PRBS band", b.omega,
        {{"PDE", gain_db(b.pde), linearize::unwrapped_phase_degrees(b.pde), "PDE (linearised pool)"},
         {"LIOM", gain_db(b.liom), linearize::unwrapped_phase_degrees(b.liom), "LIOM fitted to the recording"},
         {"LFOM", gain_db(b.lfom), linearize::unwrapped_phase_degrees(b.lfom), "LFOM fitted to the recording"}}));
  }
  return figures;
}

std::string bode_html_section(const std::vector<BodeSection>& sections, const std::string& title_tag,
                              const std::string& point_tag) {
  std::ostringstream page;
  page << "<" << title_tag << " id=\"bode\">Bode: the linearised pool against the fitted LIOM and LFOM</" << title_tag << "><p>Gate → y_dwe in mm/mm over each "
          "experiment's PRBS band (docs/linearization.md).</p>";
  const std::vector<plot::Figure> figures = bode_figures(sections);
  for (std::size_t k = 0; k < sections.size(); ++k) {
    const BodeSection& b = sections[k];
    page << "<" << point_tag << ">" << html::escape(b.experiment) << " (" << format_g(b.operating_opening_mm, 3)
         << " mm)</" << point_tag << "><p>" << html::escape(b.sentence) << "</p>" << plot::render_svg(figures[k]) << '\n';
  }
  return page.str();
}

}  // namespace canalsim::study
