#include "calibration/model_form.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>

#include "calibration/calibrate.hpp"
#include "calibration/time_offset.hpp"
#include "core/format.hpp"
#include "gates/sluice_gate.hpp"
#include "scenarios/design.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::calibration {
namespace {

using scenarios::Scenario;

// ΔBIC below which a choice pays: "very strong" evidence (Kass & Raftery 1995, 2 ln B > 10).
constexpr double kPaysBelow = -10.0;

bool fitted(const std::vector<std::string>& specs, const std::string& name) {
  return std::any_of(specs.begin(), specs.end(),
                     [&](const std::string& s) { return s.substr(0, s.find(':')) == name; });
}

// A model-form choice: when it is open, and the model with it made (the scenario edited, the
// parameters it adds appended to the specs, each starting where it changes nothing, or as near as
// its bounds allow: the refit then never ends above the calibration it extends; a parameter with
// a scan, Parameter::scan, starts where its scan finds the lowest cost).
struct FormChoice {
  std::string name, description;
  std::function<bool(const Scenario&, const std::vector<std::string>& specs)> open;
  std::function<void(Scenario&, std::vector<std::string>& specs)> make;
};

// The geometric mean of the smallest and largest positive opening the recordings command [m], or
// 0 when they command none: the rating's reference opening, where Cd ∝ (a / a_ref)^β changes
// nothing and least correlates with the coefficient itself.
double middle_commanded_opening(const std::vector<Recording>& recordings) {
  double low = std::numeric_limits<double>::infinity(), high = 0.0;
  for (const Recording& r : recordings) {
    if (!r.has(columns::gate_command)) continue;
    for (const double u : r.column(columns::gate_command)) {
      if (!(u > 0.0)) continue;
      low = std::min(low, u);
      high = std::max(high, u);
    }
  }
  return high > 0.0 ? std::sqrt(low * high) * 1e-3 : 0.0;
}

// The mean recorded level at the downstream end over the recordings, less the scenario's sensor
// offsets [m]; NaN when a recording lacks it.
double mean_end_level(const Scenario& s, const std::vector<Recording>& recordings) {
  double sum = 0.0;
  std::size_t count = 0;
  for (const Recording& r : recordings) {
    if (!r.has(columns::level_downstream_end)) return std::numeric_limits<double>::quiet_NaN();
    for (const double y : r.column(columns::level_downstream_end)) sum += y;
    count += r.size();
  }
  const double offsets_mm = s.sensors.offset_mm + s.sensors.offset_y_dwe_mm;
  return count > 0 ? (sum / static_cast<double>(count) - offsets_mm) * 1e-3 : std::numeric_limits<double>::quiet_NaN();
}

// A free weir in place of the downstream gate, its crest where it passes what the gate passes at
// the mean recorded end level h: crest = h − (Q / (C w))^(2/3) (Q = C w (h − crest)^1.5,
// scenarios/scenario.hpp), so the refit starts at the operating point the gate held.
void put_weir_in_place_of_the_gate(Scenario& s, double end_level_m) {
  const scenarios::GateSpec& gate = s.downstream.gate;
  const double q = gates::SluiceGate(scenarios::gate_geometry(gate).law).discharge(end_level_m, s.downstream.tail_level_m, gate.opening_m) *
                   gate.width_m;
  const double width = s.pools.back().bottom_width_m;
  const double wall = s.pools.back().wall_height_m;
  s.downstream.kind = scenarios::DownstreamKind::weir;
  s.downstream.weir_width_m = 0.0;  // the channel's width
  const double head = std::pow(std::max(q, 0.0) / (s.downstream.weir_coefficient * width), 2.0 / 3.0);
  s.downstream.weir_crest_m = std::clamp(end_level_m - head, 0.0, wall);
}

// Whether the scenario's reservoir and pump feed the head gate in the replay (not the recorded
// upstream level, which carries whatever the supply did): only then do the pump's choices act.
bool reservoir_drives(const Scenario& s, const std::vector<Recording>& recordings, const CalibrateOptions& o) {
  const bool recorded = o.replay.use_recorded_upstream && !recordings.empty() && recordings.front().has(columns::upstream_level);
  return s.upstream.kind == scenarios::UpstreamKind::reservoir && !recorded;
}

// The choices, in the order they are tried.
std::vector<FormChoice> form_choices(const std::vector<Recording>& recordings, const CalibrateOptions& o) {
  std::vector<FormChoice> out;
  const double reference_opening = middle_commanded_opening(recordings);
  out.push_back({"cd_opening_exponent", "the head gate's discharge coefficient a power of its opening, Cd ∝ (a / a_ref)^β (a gate rating)",
                 [reference_opening](const Scenario& x, const std::vector<std::string>& specs) {
                   return x.head_gate && x.head_gate->controlled && reference_opening > 0.0 &&
                          !fitted(specs, "cd_opening_exponent") && !fitted(specs, "cd_opening_curvature");
                 },
                 [reference_opening](Scenario& x, std::vector<std::string>& specs) {
                   scenarios::GateSpec& g = *x.head_gate;
                   // Where the rating is 1 (β = γ = 0 as the refit starts) its reference moves nothing.
                   if (g.cd_opening_exponent == 0.0 && g.cd_opening_curvature == 0.0) g.cd_reference_opening_m = reference_opening;
                   specs.push_back("cd_opening_exponent");
                 }});
  out.push_back({"zero_head_mm", "the head gate's submerged law linear in the head below a fitted head h0 (a gate running nearly drowned)",
                 [](const Scenario& x, const std::vector<std::string>& specs) { return x.head_gate && !fitted(specs, "zero_head_mm"); },
                 [](Scenario&, std::vector<std::string>& specs) { specs.push_back("zero_head_mm"); }});
  out.push_back({"border_floor_ratio", "the floor of the head gate's regime border over the tail fitted (a wide-open gate near zero head)",
                 [](const Scenario& x, const std::vector<std::string>& specs) {
                   return x.head_gate && x.head_gate->law == scenarios::GateLaw::swamee && !fitted(specs, "border_floor_ratio");
                 },
                 [](Scenario&, std::vector<std::string>& specs) { specs.push_back("border_floor_ratio"); }});
  out.push_back({"sensor_delay_s", "a time offset between the command and the levels",
                 [](const Scenario&, const std::vector<std::string>& specs) { return !fitted(specs, "sensor_delay_s"); },
                 [](Scenario&, std::vector<std::string>& specs) { specs.push_back("sensor_delay_s"); }});
  out.push_back({"weir_crest_mm", "a free weir in place of the downstream gate, its crest fitted (the gate's opening, zero head and tail dropped)",
                 [&recordings](const Scenario& x, const std::vector<std::string>&) {
                   return x.downstream.kind == scenarios::DownstreamKind::gate && !x.downstream.gate.controlled &&
                          !x.pools.empty() && std::isfinite(mean_end_level(x, recordings));
                 },
                 [&recordings](Scenario& x, std::vector<std::string>& specs) {
                   put_weir_in_place_of_the_gate(x, mean_end_level(x, recordings));
                   std::erase_if(specs, [](const std::string& spec) {
                     const std::string name = spec.substr(0, spec.find(':'));
                     return name.rfind("downstream_", 0) == 0 || name == "tail_level_mm";
                   });
                   specs.push_back("weir_crest_mm");
                 }});
  // The upstream supply, where the scenario's reservoir drives the replay: a pump whose flow lags
  // its drive (a drive's ramp, the inertia of the pump and its pipe), and the level controller's
  // gains as the recorded upstream level shows them (the scenario's are a set-up's guess). The
  // other supply form, the recorded level imposed, is the replay `--replay recorded-upstream`: it
  // leaves y_up out of the residual, so no information criterion can set it against these.
  const auto pump_open = [&recordings, &o](const std::string& name) {
    return [&recordings, &o, name](const Scenario& x, const std::vector<std::string>& specs) {
      return reservoir_drives(x, recordings, o) && !fitted(specs, name);
    };
  };
  out.push_back({"pump_lag_s", "the pump's flow lagging its drive, τ dQ/dt = k_q f − Q (a pump with its own lag)", pump_open("pump_lag_s"),
                 [](Scenario&, std::vector<std::string>& specs) { specs.push_back("pump_lag_s"); }});
  out.push_back({"pump_controller", "the pump's level controller's gains K_p and T_i fitted", pump_open("pid_kp"),
                 [](Scenario&, std::vector<std::string>& specs) {
                   if (!fitted(specs, "pid_kp")) specs.push_back("pid_kp");
                   if (!fitted(specs, "pid_ti_s")) specs.push_back("pid_ti_s");
                 }});
  out.push_back({"tail_level_mm", "the level beyond the downstream gate fitted",
                 [](const Scenario& x, const std::vector<std::string>& specs) {
                   return x.downstream.kind == scenarios::DownstreamKind::gate && !fitted(specs, "tail_level_mm");
                 },
                 [](Scenario&, std::vector<std::string>& specs) { specs.push_back("tail_level_mm"); }});
  return out;
}

// RMS level residual over the validation recordings' level channels [mm]; NaN without them.
double validation_rms(const Calibration& c) {
  double sum = 0.0;
  int count = 0;
  for (const ChannelFit& f : c.fits) {
    if (!f.validation || f.channel.rfind("y_", 0) != 0) continue;
    sum += f.rms_after * f.rms_after;
    ++count;
  }
  return count > 0 ? std::sqrt(sum / count) : std::numeric_limits<double>::quiet_NaN();
}

// The refit's options: the calibration's, one start from the estimates, no grid check or
// refinement, no laws compared.
CalibrateOptions refit_options(const Calibration& c, const CalibrateOptions& o, const std::vector<std::string>& specs) {
  CalibrateOptions one = o;
  one.parameters = specs;
  one.starts = 1;
  // The channels the calibration compared, and only those: a choice whose model produces a
  // channel the calibration's lacked would otherwise be scored on other residuals.
  one.replay.channels.clear();
  for (const ChannelFit& f : c.fits) {
    if (std::find(one.replay.channels.begin(), one.replay.channels.end(), f.channel) == one.replay.channels.end()) {
      one.replay.channels.push_back(f.channel);
    }
  }
  one.grid_refinements = 0;
  one.grid_check = false;
  one.write_grid_converged = false;
  one.gate_laws.clear();
  one.try_model_forms = false;
  return one;
}

// The trial of one choice against the refitted calibration `base`.
ModelFormTrial score(const FormChoice& choice, const Calibration& refit, const Calibration& base,
                     const std::vector<std::string>& base_specs, double effective_samples) {
  ModelFormTrial t;
  t.name = choice.name;
  t.description = choice.description;
  t.ok = refit.ok;
  t.message = refit.message;
  t.added_parameters = static_cast<int>(refit.parameters.size()) - static_cast<int>(base_specs.size());
  if (!t.ok) return t;
  t.cost = refit.cost_after;
  t.removed = 1.0 - refit.cost_after / base.cost_after;
  t.bic_change = effective_samples * std::log(refit.cost_after / base.cost_after) +
                 t.added_parameters * std::log(effective_samples);
  t.validation_rms_mm = validation_rms(refit);
  const double base_validation = validation_rms(base);
  const bool validation_not_worse = std::isnan(base_validation) || t.validation_rms_mm <= base_validation;
  t.pays = t.bic_change < kPaysBelow && validation_not_worse;
  for (const ParameterEstimate& p : refit.parameters) {
    if (!fitted(base_specs, p.name)) t.estimates.push_back({p.name, p.unit, p.value, p.std});
  }
  return t;
}

// The scenario as given, on its own grid, with the calibration's estimates on the last grid (and
// the gate law kept, when laws were compared): the choices are compared there, where a refit
// costs what the first calibration did, not 4^k times that on a grid refined k times (or on the
// finer grid of written grid-converged estimates).
Scenario estimates_on_given_grid(const Scenario& given, const Calibration& c, const std::vector<std::string>& specs) {
  Scenario s = given;
  for (const GateLawFit& l : c.gate_laws) {
    if (l.kept) s = scenarios::with_gate_law(s, l.law);
  }
  const std::vector<Parameter> parameters = select_parameters(s, specs);
  for (std::size_t j = 0; j < parameters.size() && j < c.parameters.size(); ++j) parameters[j].set(s, c.parameters[j].value);
  return s;
}

std::string verdict_of(const ModelForms& m) {
  const auto best = std::find_if(m.trials.begin(), m.trials.end(), [](const ModelFormTrial& t) { return t.pays; });
  if (best == m.trials.end()) {
    return "no model-form choice tried pays (none lowers ΔBIC below " + format_g(kPaysBelow) +
           " with a validation fit no worse and " + format_fixed(100.0 * kTimeOffsetGain, 0) +
           " % of the cost removed on twice the cells): among these the model's form does not limit the fit";
  }
  std::string line = best->name + " pays most: it removes " + format_fixed(100.0 * best->removed, 1) +
                     " % of the cost (ΔBIC " + format_fixed(best->bic_change, 0) + ")";
  if (!std::isnan(best->validation_rms_mm)) {
    line += ", validation RMS " + format_g(m.validation_rms_mm, 3) + " -> " + format_g(best->validation_rms_mm, 3) + " mm";
  }
  for (const FormEstimate& e : best->estimates) {
    line += "; " + e.name + " = " + format_g(e.value, 4) + (std::isfinite(e.std) ? " ± " + format_g(e.std, 2) : "") + " " + e.unit;
  }
  return line;
}

}  // namespace

ModelForms compare_model_forms(const Scenario& scenario, const Calibration& c, const std::vector<Recording>& recordings,
                               const std::vector<Recording>& validation, const CalibrateOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  ModelForms m;
  std::vector<std::string> specs;
  for (const ParameterEstimate& p : c.parameters) specs.push_back(p.name + ":" + format_g(p.low, 17) + ":" + format_g(p.high, 17));
  const Scenario given = estimates_on_given_grid(scenario, c, specs);
  std::vector<FormChoice> choices = form_choices(recordings, o);
  choices.erase(std::remove_if(choices.begin(), choices.end(), [&](const FormChoice& f) { return !f.open(given, specs); }),
                choices.end());
  std::size_t stage = 0;
  // The calibration and each choice on one and on twice the cells, and on top of the best.
  const std::size_t stages = 3 * choices.size() + 2;
  const auto refit = [&](const Scenario& s, const std::vector<std::string>& with, const std::string& what) {
    CalibrateOptions one = refit_options(c, o, with);
    if (o.progress) {
      const std::size_t k = std::min(stage, stages - 1);
      one.progress = [&o, k, stages, what](const ProgressReport& p) {
        o.progress({(static_cast<double>(k) + std::max(p.fraction, 0.0)) / static_cast<double>(stages),
                    "model form, " + what + ": " + p.message});
      };
    }
    ++stage;
    Calibration result = calibrate(s, recordings, validation, one);
    m.simulations += result.simulations;
    return result;
  };

  // The calibration as it stands, on the same terms as the choices.
  const Calibration base = refit(given, specs, "as calibrated");
  if (!base.ok) {
    m.message = "the calibration refitted as it stands failed: " + base.message;
    return m;
  }
  m.cost = base.cost_after;
  m.validation_rms_mm = validation_rms(base);
  m.effective_samples = static_cast<double>(base.samples) / std::max(1.0, base.inflation);

  // Each choice alone.
  std::vector<Scenario> made(choices.size(), given);
  std::vector<std::vector<std::string>> made_specs(choices.size(), specs);
  std::vector<Calibration> alone;
  for (std::size_t k = 0; k < choices.size(); ++k) {
    choices[k].make(made[k], made_specs[k]);
    alone.push_back(refit(made[k], made_specs[k], choices[k].name));
    m.trials.push_back(score(choices[k], alone.back(), base, specs, m.effective_samples));
    m.trials.back().note = alone.back().scan_note;
  }

  // On the scenario's grid a choice can pay by standing in for the discretisation (a time offset
  // for the scheme's phase error): each choice that pays is refitted on twice the cells too, and
  // keeps "pays" only if it still pays there.
  if (std::any_of(m.trials.begin(), m.trials.end(), [](const ModelFormTrial& t) { return t.pays; })) {
    const Calibration finer_base = refit(scenarios::with_cells_multiplied(base.calibrated, 2), specs, "as calibrated, twice the cells");
    for (std::size_t k = 0; k < choices.size() && finer_base.ok; ++k) {
      if (!m.trials[k].pays) continue;
      const std::string finer_cells = std::to_string(2 * given.pools.front().cells) + " cells";
      const ModelFormTrial finer =
          score(choices[k], refit(scenarios::with_cells_multiplied(alone[k].calibrated, 2), made_specs[k], choices[k].name + ", twice the cells"),
                finer_base, specs, m.effective_samples);
      // Material as the calibration's own time-offset scan asks of a delay (time_offset.hpp):
      // a share of the cost, here on the finer grid, where the discretisation's is smaller.
      m.trials[k].pays = finer.pays && finer.removed >= kTimeOffsetGain;
      m.trials[k].note += std::string(m.trials[k].note.empty() ? "" : "; ") +
                          (m.trials[k].pays ? "pays on " + finer_cells + " too"
                          : finer.pays      ? "removes less than " + format_fixed(100.0 * kTimeOffsetGain, 0) + " % on " + finer_cells
                                            : "does not pay on " + finer_cells + ": it stood in for the discretisation") +
                         " (removes " + format_fixed(100.0 * finer.removed, 1) + " %, ΔBIC " + format_fixed(finer.bic_change, 0) + " there)";
    }
  }
  // A choice can also pay alone by standing in for a better one (a regularised gate law for a
  // tail level it does not know): each other choice that still pays is refitted on top of the
  // one that pays most, and keeps "pays" only if it pays there too.
  const auto best = std::min_element(m.trials.begin(), m.trials.end(), [](const ModelFormTrial& a, const ModelFormTrial& b) {
    return a.pays && (!b.pays || a.bic_change < b.bic_change);
  });
  if (best != m.trials.end() && best->pays) {
    const std::size_t b = static_cast<std::size_t>(best - m.trials.begin());
    for (std::size_t k = 0; k < choices.size(); ++k) {
      if (k == b || !m.trials[k].pays) continue;
      Scenario both = alone[b].calibrated;  // from the best choice's estimates
      std::vector<std::string> both_specs = made_specs[b];
      if (!choices[k].open(both, both_specs)) {  // a tail level beyond a weir that replaced the gate
        m.trials[k].pays = false;
        m.trials[k].note += "; does not apply with " + choices[b].name;
        continue;
      }
      choices[k].make(both, both_specs);
      const ModelFormTrial on_best = score(choices[k], refit(both, both_specs, choices[k].name + " with " + choices[b].name),
                                           alone[b], made_specs[b], m.effective_samples);
      // Beyond the best as on twice the cells: a material share of what is left, not a sliver
      // that the information criterion alone would let pay on long recordings.
      m.trials[k].pays = on_best.pays && on_best.removed >= kTimeOffsetGain;
      m.trials[k].note += std::string("; ") + (m.trials[k].pays ? "pays beyond " : "not beyond ") + choices[b].name +
                          " (removes " + format_fixed(100.0 * on_best.removed, 1) + " %, ΔBIC " +
                          format_fixed(on_best.bic_change, 0) + " on top of it)";
    }
  }
  // Where each choice removes the residual: its own grid's refit against the reference.
  std::vector<ChoiceSeries> shares;
  for (std::size_t k = 0; k < choices.size(); ++k) {
    if (alone[k].ok) shares.push_back({choices[k].name, &alone[k].series});
  }
  m.breakdown = residual_breakdown(base.series, shares);
  std::stable_sort(m.trials.begin(), m.trials.end(), [](const ModelFormTrial& a, const ModelFormTrial& b) {
    if (a.ok != b.ok) return a.ok;
    return a.ok && a.bic_change < b.bic_change;
  });
  m.done = true;
  m.verdict = verdict_of(m);
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return m;
}

}  // namespace canalsim::calibration
