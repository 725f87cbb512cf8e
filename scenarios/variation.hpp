// The same canal, simulated or built differently: what an independent simulator or the real canal
// would differ in. Tests and the realistic blind test (diagnosis/blindtest.hpp) make their truths
// with it, so that the model a fit or a diagnosis uses cannot represent the truth exactly — if
// the truth were simulated by the very model that is then fitted, every modelling choice (grid,
// limiter, Courant number, gate law) would cancel and prove only that the code agrees with itself.
//
//   independent_truth()   the numerics: more cells, the other limiter, a smaller Courant number,
//                         optionally the paper's simple gate laws (eqs. 9, 11) instead of Swamee's;
//   perturb_uncertain()   the physics a laboratory does not know exactly, each drawn within its
//                         tolerance: the head gate's free and submerged discharge
//                         coefficients, every pool's Manning n, the downstream gate's opening, the
//                         tail level, and every level sensor's offset.
#pragma once

#include <random>
#include <string>

#include "scenarios/scenario.hpp"

namespace canalsim::scenarios {

struct TruthVariation {
  int cells_factor = 4;           // cells of every pool multiplied by this
  bool swap_limiter = true;       // van Leer <-> minmod
  double cfl = 0.45;              // Courant number of the truth
  // The paper's eqs. 9/11 at every gate (head, between pools, downstream), free and submerged
  // with one discharge coefficient Cd (not a multiplier: the truth's gates pass Cd a sqrt(2 g h)).
  bool simple_gate_laws = false;
  double simple_discharge_coefficient = 0.6;
};

Scenario independent_truth(Scenario s, const TruthVariation& v = {});

// The scenario on `factor` times the cells of every pool (its per-cell design profiles, which
// belong to the old grid, dropped). Truths, the calibration's grid check and its refinement use it.
Scenario with_cells_multiplied(Scenario s, int factor);

// The scenario on 1/`divisor` of the cells of every pool (rounded up, at least two a pool; its
// per-cell design profiles dropped likewise). The diagnosis' searches replay on it.
Scenario with_cells_divided(Scenario s, int divisor);

// The scenario with `law` at every sluice gate (head, between pools, downstream), coefficients
// unchanged (they multiply the law's published one). Calibration compares laws with it.
Scenario with_gate_law(Scenario s, GateLaw law);
// Whether the scenario has a sluice gate a law applies to.
bool has_sluice_gate(const Scenario& s);

// Calls visit(table, gate) for every sluice gate a law applies to — the head gate, the gates
// between pools, the downstream gate — with its scenario table ("head_gate", "gates[2]",
// "downstream.gate"; the keys of calibration/scenario_file.hpp). S is Scenario or const Scenario.
template <class S, class Visit>
void for_each_sluice_gate(S& s, Visit visit) {
  if (s.head_gate) visit(std::string("head_gate"), *s.head_gate);
  for (std::size_t i = 0; i < s.gates.size(); ++i) visit("gates[" + std::to_string(i + 1) + "]", s.gates[i]);
  if (s.downstream.kind == DownstreamKind::gate) visit(std::string("downstream.gate"), s.downstream.gate);
}

// Tolerances of the physics a laboratory does not know (each drawn uniformly within ±).
struct UncertainTolerances {
  double discharge_coefficient = 0.05;  // relative, free and submerged drawn independently
  double manning_n = 0.25;              // relative, per pool
  double downstream_opening_mm = 1.0;
  double tail_level_mm = 1.0;           // only where the downstream gate has a tail level
  double level_offset_mm = 0.5;         // per level sensor
};

// The scenario with its uncertain parameters drawn within the tolerances; `drawn` (optional)
// gets one line per parameter ("cd_free ×1.032", "offset_y_dwe_mm +0.21", ...).
Scenario perturb_uncertain(Scenario s, const UncertainTolerances& tolerances, std::mt19937_64& rng,
                           std::string* drawn = nullptr);

}  // namespace canalsim::scenarios
