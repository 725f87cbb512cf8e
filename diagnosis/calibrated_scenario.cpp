#include "diagnosis/calibrated_scenario.hpp"

#include <cmath>
#include <map>
#include <stdexcept>

#include "calibration/parameters.hpp"
#include "calibration/scenario_file.hpp"
#include "core/format.hpp"
#include "core/recording.hpp"
#include "diagnosis/baseline.hpp"
#include "scenarios/scenario_toml.hpp"
#include "scenarios/variation.hpp"

namespace canalsim::diagnosis {
namespace {

// The scenario key of every sluice gate's law ("head_gate.law", "gates[2].law",
// "downstream.gate.law"; scenario_file.hpp) with the law it holds.
std::vector<std::pair<std::string, scenarios::GateLaw>> gate_law_keys(const scenarios::Scenario& s) {
  std::vector<std::pair<std::string, scenarios::GateLaw>> keys;
  scenarios::for_each_sluice_gate(
      s, [&keys](const std::string& table, const scenarios::GateSpec& g) { keys.emplace_back(table + ".law", g.law); });
  return keys;
}

// "swamee: cost 0.18; simple: cost 0.031"
std::string compared_laws(const calibration::Calibration& c) {
  std::string text;
  for (const auto& l : c.gate_laws) {
    text += (text.empty() ? "" : "; ") + std::string(scenarios::to_string(l.law)) + ": " +
            (l.ok ? "cost " + format_g(l.cost_after, 3) : "failed");
  }
  return text;
}

// The value the calibrated scenario holds for `p` (Calibration::written_grid_converged).
double written_value(const calibration::Calibration& c, const calibration::ParameterEstimate& p) {
  return c.written_grid_converged ? p.converged : p.value;
}

}  // namespace

std::string calibrated_scenario_toml(const std::string& text, const calibration::Calibration& c,
                                     const CalibratedScenarioSource& source) {
  std::vector<calibration::KeyEdit> edits;
  for (const auto& p : c.parameters) {
    const std::string spread = std::isfinite(p.std) ? "± " + format_g(p.std, 2) : "std not determined";
    // The key holds the value for the model written: the estimate for the grid calibrated on, or
    // the grid-converged estimate on a finer grid (Calibration::written_grid_converged).
    const std::string converged = !c.grid.done                ? ""
                                  : c.written_grid_converged ? "; written: its grid-converged value " + format_g(p.converged, 6)
                                                              : "; grid-converged " + format_g(p.converged, 6);
    edits.push_back({p.key, written_value(c, p) * p.key_scale,
                     "calibrated: " + p.name + " = " + format_g(p.value, 6) + " " + spread + " " + p.unit + " (was " +
                         format_g(p.start, 6) + converged + ")",
                     ""});
  }
  if (!c.gate_laws.empty()) {  // the laws compared, as the calibrated scenario carries them
    for (const auto& [key, law] : gate_law_keys(c.calibrated)) {
      std::string quoted_law = "\"";
      quoted_law.append(scenarios::to_string(law)).push_back('"');
      edits.push_back({key, 0.0, "calibrated: the gate law that fits best (" + compared_laws(c) + ")", quoted_law});
    }
  }
  for (std::size_t i = 0; (c.grids.size() > 1 || c.written_grid_converged) && i < c.calibrated.pools.size(); ++i) {
    const int cells = c.calibrated.pools[i].cells;
    const std::string was = std::to_string(c.grids.empty() ? cells / c.written_cells_factor : c.grids.front()[i]);
    const std::string times = c.written_cells_factor == 2 ? "twice" : std::to_string(c.written_cells_factor) + " times";
    const std::string note = c.written_grid_converged
                                 ? times + " the cells of the last grid calibrated on (was " + was + "; " + c.grid_note +
                                       "), with the grid-converged estimates"
                                 : "calibrated on this grid (was " + was + "): " + c.grid_note;
    edits.push_back({"pools[" + std::to_string(i + 1) + "].cells", 0.0, note, std::to_string(c.calibrated.pools[i].cells)});
  }
  std::string recordings;
  for (const auto& r : source.recordings) recordings += " " + r;
  std::map<std::string, double> deviations;  // [calibration.std]: what diagnose takes as left open
  for (const auto& p : c.parameters) deviations[p.name] = left_open(p);
  std::string out = "# Calibrated by canalsim calibrate from " + source.scenario + " on" + recordings + "\n" +
                    calibration::with_calibration_table(calibration::edit_scenario_toml(text, edits), deviations,
                                                        baseline_rms_of(c, columns::level_downstream_end),
                                                        calibrated_std_alone_of(c),
                                                        baseline_rms_by_channel(c), baseline_slow_rms_by_channel(c));
  const scenarios::Scenario back = scenarios::parse_scenario(out, source.destination);
  for (std::size_t j = 0; j < c.parameters.size(); ++j) {
    const auto catalog = calibration::select_parameters(back, {c.parameters[j].name + ":" + format_g(c.parameters[j].low, 17) +
                                                               ":" + format_g(c.parameters[j].high, 17)});
    const double read = catalog.front().get(back);
    const double expected = written_value(c, c.parameters[j]);
    if (std::abs(read - expected) > 1e-8 * std::max(1.0, std::abs(read))) {
      throw std::runtime_error("calibrated scenario: " + c.parameters[j].key + " reads back as " + format_g(read) +
                               ", expected " + format_g(expected));
    }
  }
  if (!c.gate_laws.empty() && gate_law_keys(back) != gate_law_keys(c.calibrated)) throw std::runtime_error("calibrated scenario: the gate laws do not read back");
  for (std::size_t i = 0; i < back.pools.size() && i < c.calibrated.pools.size(); ++i) {
    if (back.pools[i].cells != c.calibrated.pools[i].cells) throw std::runtime_error("calibrated scenario: the grid does not read back");
  }
  return out;
}


}  // namespace canalsim::diagnosis
