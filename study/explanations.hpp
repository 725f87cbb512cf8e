// Why a conclusion of the paper does not hold on the simulated laboratory canal (the Saint-Venant
// truth of `canalsim simulate lab`): one sentence on the physics behind it, with this study's own
// figures in it, and the figure or page that shows it. The causes are the ones docs/lab-canal.md
// and docs/linearization.md measure: free-flow gains the simulated flume cannot have, a pool whose
// gain hardly changes across the PRBS band (so its order has little to act on), a ±5 mm PRBS that
// leaves the head term of the nonlinear models nearly constant (so γ is not determined), regimes
// judged on instantaneous levels that lag the gate, and a command sampled on the recorder's grid.
#pragma once

#include <string>

#include "study/study.hpp"

namespace canalsim::study {

// The explanation of a claim that does not hold; empty for a claim that holds or whose failure
// none of the causes above explains.
std::string why_it_fails(const Claim& claim, const StudyResult& result);

}  // namespace canalsim::study
