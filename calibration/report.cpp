#include "calibration/report.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "calibration/time_offset.hpp"
#include "core/json.hpp"
#include "core/format.hpp"

namespace canalsim::calibration {
namespace {

std::string pad(std::string s, std::size_t width) {
  if (s.size() < width) s += std::string(width - s.size(), ' ');
  return s;
}

std::string lpad(std::string s, std::size_t width) {
  if (s.size() < width) s = std::string(width - s.size(), ' ') + s;
  return s;
}

std::string value_text(double v) { return std::isfinite(v) ? format_g(v, 5) : "inf"; }

nlohmann::json breakdown_json(const ResidualBreakdown& b) {
  using nlohmann::json;
  json j = {{"choices", b.choices}, {"groups", json::array()}};
  for (const BreakdownGroup& g : b.groups) {
    json entry = {{"axis", g.axis}, {"name", g.name}, {"samples", g.samples}, {"rms_mm", g.rms_mm}, {"mean_mm", g.mean_mm}};
    if (!b.choices.empty()) {
      entry["removed"] = json::object();
      for (std::size_t k = 0; k < b.choices.size() && k < g.removed.size(); ++k) entry["removed"][b.choices[k]] = json_number(g.removed[k]);
    }
    j["groups"].push_back(entry);
  }
  return j;
}

nlohmann::json model_forms_json(const ModelForms& m) {
  using nlohmann::json;
  json j = {{"done", m.done}, {"message", m.message}, {"cost", m.cost}, {"effective_samples", m.effective_samples},
            {"verdict", m.verdict}, {"seconds", m.seconds}, {"simulations", m.simulations}};
  j["validation_rms_mm"] = json_number(m.validation_rms_mm);
  j["breakdown"] = breakdown_json(m.breakdown);
  j["trials"] = json::array();
  for (const ModelFormTrial& t : m.trials) {
    json entry = {{"name", t.name}, {"description", t.description}, {"added_parameters", t.added_parameters}, {"ok", t.ok}};
    if (!t.ok) {
      entry["message"] = t.message;
    } else {
      entry.update({{"cost", t.cost}, {"removed", t.removed}, {"bic_change", t.bic_change}, {"pays", t.pays}, {"note", t.note}});
      entry["validation_rms_mm"] = json_number(t.validation_rms_mm);
      entry["estimates"] = json::array();
      for (const FormEstimate& e : t.estimates) {
        entry["estimates"].push_back({{"name", e.name}, {"unit", e.unit}, {"value", e.value}, {"std", json_number(e.std)}});
      }
    }
    j["trials"].push_back(entry);
  }
  return j;
}

std::string std_text(const ParameterEstimate& p) {
  if (!std::isfinite(p.std)) return "not determined";
  return format_g(p.std, 2);
}

}  // namespace

std::string gate_law_lines(const Calibration& c) {
  std::string out = "gate laws compared (each calibrated; the lowest cost kept):\n";
  for (const auto& l : c.gate_laws) {
    out += "  " + pad(scenarios::to_string(l.law), 8) +
           (l.ok ? "cost per sample " + format_g(l.cost_after, 4) : "failed: " + l.message) + (l.kept ? "  (kept)" : "") + "\n";
  }
  return out;
}

std::string model_form_lines(const Calibration& c) {
  const ModelForms& m = c.model_forms;
  if (!m.done) return m.message.empty() ? "" : "model form: " + m.message + "\n";
  const bool validated = !std::isnan(m.validation_rms_mm);
  const auto validation = [&](double rms) { return validated ? "  validation " + format_g(rms, 3) + " mm" : std::string(); };
  std::string out = "model form (each choice added and refitted from the estimates; it pays at ΔBIC < -10 on " +
                    format_fixed(m.effective_samples, 0) + " effective samples" +
                    (validated ? ", a validation fit no worse" : "") + " and " + format_fixed(100.0 * kTimeOffsetGain, 0) + " % of the cost removed on twice the cells):\n";
  out += "  " + pad("as calibrated", 22) + "cost " + format_g(m.cost, 4) + validation(m.validation_rms_mm) + "\n";
  for (const ModelFormTrial& t : m.trials) {
    out += "  " + pad(t.name, 22);
    if (!t.ok) {
      out += "failed: " + t.message + "\n";
      continue;
    }
    out += "cost " + pad(format_g(t.cost, 4), 8) + " removes " + lpad(format_fixed(100.0 * t.removed, 1), 5) + " %  ΔBIC " +
           lpad(format_fixed(t.bic_change, 0), 6) + validation(t.validation_rms_mm) + (t.pays ? "  pays" : "") +
           (t.note.empty() ? "" : "  (" + t.note + ")") + "\n";
  }
  return out + "  -> " + m.verdict + "\n";
}

std::string breakdown_lines(const Calibration& c) {
  const bool shares = c.model_forms.done && !c.model_forms.breakdown.choices.empty();
  const ResidualBreakdown& b = shares ? c.model_forms.breakdown : c.breakdown;
  if (b.groups.empty()) return "";
  std::string out = shares ? "where the residual lives (the reference refitted for the model form; level channels, recorded − model;\n"
                             " each choice's column: the share of the group's squared residual its refit removes):\n"
                           : "where the residual lives (level channels, recorded − model):\n";
  std::size_t gw = 14;
  for (const BreakdownGroup& g : b.groups) gw = std::max(gw, g.name.size() + 2);
  out += "  " + pad("axis", 17) + pad("group", gw) + lpad("samples", 8) + lpad("RMS mm", 9) + lpad("mean mm", 9);
  std::vector<std::size_t> widths;
  for (const std::string& name : b.choices) {
    widths.push_back(std::max<std::size_t>(name.size(), 7) + 2);
    out += lpad(name, widths.back());
  }
  out += "\n";
  std::string axis;
  for (const BreakdownGroup& g : b.groups) {
    out += "  " + pad(g.axis == axis ? "" : g.axis, 17) + pad(g.name, gw) + lpad(std::to_string(g.samples), 8) +
           lpad(format_fixed(g.rms_mm, 3), 9) + lpad(format_fixed(g.mean_mm, 3), 9);
    axis = g.axis;
    for (std::size_t k = 0; k < widths.size() && k < g.removed.size(); ++k) {
      out += lpad(std::isfinite(g.removed[k]) ? format_fixed(100.0 * g.removed[k], 0) + " %" : "-", widths[k]);
    }
    out += "\n";
  }
  return out;
}

std::string grid_lines(const Calibration& c) {
  if (c.grids.empty()) return "";
  std::string cells;
  for (const auto& grid : c.grids) {
    int total = 0;
    for (int n : grid) total += n;
    cells += (cells.empty() ? "" : " -> ") + std::to_string(total);
  }
  return "grid: " + cells + " cells (" + c.grid_note + ")\n";
}

std::string text_summary(const Calibration& c) {
  std::ostringstream out;
  if (!c.ok) {
    out << "calibration failed: " << c.message << "\n";
    return out.str();
  }
  std::size_t w = 9;
  for (const auto& p : c.parameters) w = std::max(w, p.name.size() + 2);
  out << pad("parameter", w) << lpad("start", 12) << lpad("estimate", 12) << "  " << pad("± std", 16)
      << pad("(numerics)", 12) << pad("converged", 12) << pad("bounds", 22) << "unit\n";
  for (const auto& p : c.parameters) {
    out << pad(p.name, w) << lpad(value_text(p.start), 12) << lpad(value_text(p.value), 12) << "  "
        << pad(std::string("± ").append(std_text(p)), 16) << pad(c.grid.done ? format_g(p.grid_shift, 2) : "-", 12)
        << pad(c.grid.done ? value_text(p.converged) : "-", 12) << pad(std::string("[").append(format_g(p.low, 4)).append(", ").append(format_g(p.high, 4)).append("]"), 22) << p.unit
        << (p.at_bound ? "  (at a bound)" : "") << "\n";
  }
  if (c.grid.done) {
    out << "(numerics: the part of the std that is how far the estimates move on other numerics — twice the\n"
           " cells (counted twice, Richardson), the other limiter, half the Courant number; converged: the\n"
           " estimate extrapolated to a grid without discretisation error, for a measured value or a model on\n"
           " another grid; the scenario written holds the estimates, or the converged values on twice the\n"
           " cells when they fit better: \"model written\" below)\n";
  }
  if (!c.identifiability.empty()) {
    out << "\nnot identifiable from these recordings:\n";
    for (const auto& u : c.identifiability) {
      std::string names;
      for (const auto& n : u.parameters) names += (names.empty() ? "" : ", ") + n;
      out << "  " << names << ": " << u.reason;
      if (!u.determined.empty()) out << "; determined: " << u.determined;
      out << "\n";
    }
  }
  std::size_t rw = 10;
  for (const auto& f : c.fits) rw = std::max(rw, std::min<std::size_t>(f.recording.size(), 30) + 3);
  out << "\n" << pad("recording", rw) << pad("channel", 10) << lpad("RMS before", 12) << lpad("after", 10)
      << lpad("Nrmse before", 14) << lpad("after", 9) << "\n";
  for (const auto& f : c.fits) {
    std::string name = f.recording;
    if (name.size() > 30) name = "..." + name.substr(name.size() - 27);
    out << pad(name + (f.validation ? " *" : ""), rw) << pad(f.channel, 10) << lpad(format_fixed(f.rms_before, 3), 12)
        << lpad(format_fixed(f.rms_after, 3), 10) << lpad(format_fixed(f.nrmse_before, 1) + " %", 14)
        << lpad(format_fixed(f.nrmse_after, 1) + " %", 9) << "\n";
  }
  if (std::any_of(c.fits.begin(), c.fits.end(), [](const ChannelFit& f) { return f.validation; })) {
    out << "(* validation recording, not used in the fit; RMS in mm or l/s)\n";
  }
  out << "\nweighted cost per sample " << format_g(c.cost_before, 4) << " -> " << format_g(c.cost_after, 4)
      << "; residual autocorrelation inflates the variances " << format_fixed(c.inflation, 1) << "x\n";
  if (c.grid.done) out << "grid check: " << c.grid.verdict << "\n";
  if (!c.gate_laws.empty()) out << gate_law_lines(c);
  out << grid_lines(c);
  out << model_form_lines(c);
  out << breakdown_lines(c);
  if (!c.time_offset_note.empty()) out << "time offset: " << c.time_offset_note << "\n";
  if (!c.written_note.empty()) out << "model written: " << c.written_note << "\n";
  out << c.simulations << " simulations, " << c.starts << " start(s), " << c.iterations << " iterations, "
      << format_fixed(c.seconds, 1) << " s\n";
  if (!c.starts_note.empty()) out << "(" << c.starts_note << ")\n";
  if (!c.scan_note.empty()) out << "(" << c.scan_note << ")\n";
  return out.str();
}

nlohmann::json to_json(const Calibration& c) {
  using nlohmann::json;
  json j;
  j["ok"] = c.ok;
  if (!c.ok) j["message"] = c.message;
  j["parameters"] = json::array();
  for (const auto& p : c.parameters) {
    j["parameters"].push_back({{"name", p.name}, {"unit", p.unit}, {"key", p.key}, {"start", p.start},
                               {"value", p.value}, {"std", json_number(p.std)}, {"statistical_std", json_number(p.statistical_std)},
                               {"numerical_std", p.grid_shift}, {"converged_value", p.converged}, {"low", p.low}, {"high", p.high},
                               {"at_bound", p.at_bound}, {"sensitivity", p.sensitivity}});
  }
  json corr = json::array();
  for (const auto& row : c.correlation) {
    json r = json::array();
    for (double v : row) r.push_back(json_number(v));
    corr.push_back(r);
  }
  j["correlation"] = corr;
  j["identifiability"] = json::array();
  for (const auto& u : c.identifiability) {
    j["identifiability"].push_back({{"parameters", u.parameters}, {"reason", u.reason}, {"determined", u.determined}});
  }
  j["fits"] = json::array();
  for (const auto& f : c.fits) {
    j["fits"].push_back({{"recording", f.recording}, {"channel", f.channel}, {"validation", f.validation},
                         {"rms_before", f.rms_before}, {"rms_after", f.rms_after}, {"nrmse_before", f.nrmse_before},
                         {"nrmse_after", f.nrmse_after}});
  }
  if (c.grid.done) {
    j["grid_check"] = {{"factor", c.grid.factor}, {"cost", c.grid.cost}, {"refined_cost", c.grid.refined_cost},
                       {"rms_change_mm", c.grid.rms_change}, {"residual_rms_mm", c.grid.residual_rms},
                       {"verdict", c.grid.verdict}};
  }
  j["discretisation"] = json::array();
  for (const auto& d : c.discretisation) {
    j["discretisation"].push_back({{"numerics", d.name}, {"weight", d.weight}, {"shift", d.shift},
                                   {"linear_response", d.linear_response}, {"cost", d.cost}});
  }
  j["gate_laws"] = json::array();
  for (const auto& l : c.gate_laws) {
    json entry = {{"law", scenarios::to_string(l.law)}, {"ok", l.ok}, {"kept", l.kept}};
    if (l.ok) entry["cost_after"] = l.cost_after;
    if (!l.ok) entry["message"] = l.message;
    j["gate_laws"].push_back(entry);
  }
  j["residual_breakdown"] = breakdown_json(c.breakdown);
  if (c.model_forms.done || !c.model_forms.message.empty()) j["model_forms"] = model_forms_json(c.model_forms);
  j["grids"] = c.grids;
  j["grid_note"] = c.grid_note;
  j["time_offset_note"] = c.time_offset_note;
  j["written_grid_converged"] = c.written_grid_converged;
  j["written_note"] = c.written_note;
  j["warnings"] = c.warnings;
  j["cost_before"] = c.cost_before;
  j["cost_after"] = c.cost_after;
  j["autocorrelation_inflation"] = c.inflation;
  j["samples"] = c.samples;
  j["simulations"] = c.simulations;
  j["starts"] = c.starts;
  j["starts_note"] = c.starts_note;
  j["scan_note"] = c.scan_note;
  j["iterations"] = c.iterations;
  j["seconds"] = c.seconds;
  j["solver"] = c.solver_report;
  return j;
}

}  // namespace canalsim::calibration
