// `canalsim fit ... --freq-check SCENARIO`: the fitted reduced models held against the
// linearised Saint-Venant pool over each recording's PRBS band (docs/linearization.md §7).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "reduced_models/identification.hpp"
#include "scenarios/scenario.hpp"

namespace canalsim::cli {

// The scenario experiment each recording was simulated from (its "experiment" metadata), checked
// before any fit runs; throws InputError naming --freq-check and the recording.
std::vector<const scenarios::ExperimentSpec*> freq_check_experiments(const scenarios::Scenario& scenario,
                                                                      const std::vector<std::string>& recordings);

// Prints, per fit, the model's and the PDE's responses compared over the band, and returns them
// as JSON (one entry per fit).
nlohmann::json print_freq_check(const scenarios::Scenario& scenario,
                                const std::vector<const scenarios::ExperimentSpec*>& experiments,
                                const std::vector<reduced::FitResult>& fits,
                                const std::vector<reduced::ExperimentData>& data);

}  // namespace canalsim::cli
