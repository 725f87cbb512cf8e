// What a sweep computes for one case ([compute], docs/sweep.md "The table"): the recording's
// summary, reduced models fitted to it, the linearised pool, the diagnosis against the base
// scenario. Each figure is one column, its unit in its name.
#pragma once

#include <string>
#include <vector>

#include "core/recording.hpp"
#include "reduced_models/models.hpp"
#include "scenarios/scenario.hpp"
#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {

// The computed columns, in the table's order.
std::vector<std::string> computed_columns(const Computations& compute);
// A reduced model's name as its columns start: "LFOM", "NLIOM_F".
std::string model_column_prefix(reduced::ModelKind kind);

// The computed cells of a case, one per computed column ("" where a figure is not defined: the
// band's λ of an experiment without a PRBS), and what the run warned about.
struct CaseFigures {
  std::vector<std::string> cells;
  std::vector<std::string> warnings;
};

// Simulates `experiment` on the case's `scenario` and computes what `compute` asks; `base` is
// the sweep's base scenario, the model the diagnosis compares the recording with. A run without a
// steady state, a run or fit refused as too long, a failed fit or diagnosis throws.
CaseFigures compute_case(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment,
                         const scenarios::Scenario& base, const Computations& compute);

// The simulation every case starts from: the experiment run to its end, its steady state required
// (a canal that has none fails the case rather than starting from a marched state).
Recording simulate_case(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment,
                        std::vector<std::string>* warnings = nullptr);

}  // namespace canalsim::sweep
