#include "scenarios/variation.hpp"

#include "core/format.hpp"
#include "gates/sluice_gate.hpp"

#include <algorithm>
#include <utility>

namespace canalsim::scenarios {
namespace {

double uniform_within(std::mt19937_64& rng, double tolerance) {
  return tolerance > 0.0 ? std::uniform_real_distribution<double>(-tolerance, tolerance)(rng) : 0.0;
}

void note(std::string* drawn, const std::string& line) {
  if (drawn) *drawn += (drawn->empty() ? "" : "; ") + line;
}

// The scenario with each pool's cells `regridded(cells)`.
template <class Regrid>
Scenario on_another_grid(Scenario s, Regrid regridded) {
  for (auto& pool : s.pools) {
    pool.cells = regridded(pool.cells);
    pool.design_depth_m.clear();  // per-cell design profiles belong to the old grid
    pool.design_discharge_m3s.clear();
  }
  return s;
}

}  // namespace

Scenario with_cells_multiplied(Scenario s, int factor) {
  return on_another_grid(std::move(s), [factor](int cells) { return cells * factor; });
}

Scenario with_cells_divided(Scenario s, int divisor) {
  return on_another_grid(std::move(s), [divisor](int cells) { return std::max(2, (cells + divisor - 1) / divisor); });
}

Scenario independent_truth(Scenario s, const TruthVariation& v) {
  s = with_cells_multiplied(std::move(s), v.cells_factor);
  if (v.swap_limiter) s.numerics.van_leer_limiter = !s.numerics.van_leer_limiter;
  s.numerics.cfl = v.cfl;
  if (v.simple_gate_laws) {
    // A scenario's coefficient multiplies the law's published one (scenarios/design.cpp
    // gate_geometry), for the simple laws Cd = 0.6: the truth's Cd becomes that multiplier. The
    // submerged multiplier is the same (eqs. 9 and 11 share Cd), so it is unset.
    const double multiplier = v.simple_discharge_coefficient / gates::SluiceGateOptions{}.simple_discharge_coefficient;
    s = with_gate_law(std::move(s), GateLaw::simple);
    for_each_sluice_gate(s, [multiplier](const std::string&, GateSpec& g) {
      g.discharge_coefficient = multiplier;
      g.submerged_discharge_coefficient.reset();
    });
  }
  return s;
}

Scenario with_gate_law(Scenario s, GateLaw law) {
  for_each_sluice_gate(s, [law](const std::string&, GateSpec& g) { g.law = law; });
  return s;
}

bool has_sluice_gate(const Scenario& s) {
  bool any = false;
  for_each_sluice_gate(s, [&any](const std::string&, const GateSpec&) { any = true; });
  return any;
}

Scenario perturb_uncertain(Scenario s, const UncertainTolerances& t, std::mt19937_64& rng, std::string* drawn) {
  if (s.head_gate) {
    GateSpec& g = *s.head_gate;
    const double free_factor = 1.0 + uniform_within(rng, t.discharge_coefficient);
    const double submerged_factor = 1.0 + uniform_within(rng, t.discharge_coefficient);
    const double submerged = g.submerged_coefficient();
    g.discharge_coefficient *= free_factor;
    g.submerged_discharge_coefficient = submerged * submerged_factor;
    note(drawn, "cd_free x" + format_fixed(free_factor, 3) + ", cd_submerged x" + format_fixed(submerged_factor, 3));
  }
  for (std::size_t i = 0; i < s.pools.size(); ++i) {
    const double factor = 1.0 + uniform_within(rng, t.manning_n);
    s.pools[i].manning_n *= factor;
    std::string name = "manning_n";
    if (s.pools.size() > 1) name += '.' + std::to_string(i + 1);  // the calibration's names
    note(drawn, name + " x" + format_fixed(factor, 3));
  }
  if (s.downstream.kind == DownstreamKind::gate) {
    const double opening_mm = uniform_within(rng, t.downstream_opening_mm);
    s.downstream.gate.opening_m += 1e-3 * opening_mm;
    note(drawn, "downstream_opening_mm " + format_fixed(opening_mm, 3));
    if (s.downstream.tail_level_m > 0.0) {
      const double tail_mm = uniform_within(rng, t.tail_level_mm);
      s.downstream.tail_level_m += 1e-3 * tail_mm;
      note(drawn, "tail_level_mm " + format_fixed(tail_mm, 3));
    }
  }
  SensorSpec& sensors = s.sensors;
  for (auto [name, offset] : {std::pair{"offset_y_up_mm", &sensors.offset_y_up_mm},
                              std::pair{"offset_y_dw_mm", &sensors.offset_y_dw_mm},
                              std::pair{"offset_y_dwe_mm", &sensors.offset_y_dwe_mm}}) {
    const double d = uniform_within(rng, t.level_offset_mm);
    *offset += d;
    note(drawn, std::string(name) + " " + format_fixed(d, 3));
  }
  return s;
}

}  // namespace canalsim::scenarios
