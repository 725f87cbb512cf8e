// Fitting indexes of the paper (Section 5):
//   Nrmse (eq. 19) = 100 (1 − ‖ŷ − y‖₂ / ‖y − mean(y)‖₂)  — a fit percentage (MATLAB's
//                    `compare` / goodnessOfFit 'NRMSE' fit): 100 is perfect, 0 is no better than
//                    the mean, it can be negative.
//   IAE   (eq. 20) = ∫ |ŷ − y| dt, evaluated as h Σ_k |ŷ_k − y_k| (rectangle rule).
//   IAE_c (eq. 21) = Σ_j IAE_j over several recordings.
//   Δp    (eq. 22) = max_j |p_j − p_c| / |p_c|: deviation of per-recording parameters p_j from the
//                    nominal p_c.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "reduced_models/models.hpp"

namespace canalsim::reduced {

// Both throw std::invalid_argument when the lengths differ or are zero.
double nrmse_percent(const std::vector<double>& model, const std::vector<double>& data);
double iae(const std::vector<double>& model, const std::vector<double>& data, double h);
// Σ_j iae(model_j, data_j, h_j).
double iae_combined(const std::vector<std::vector<double>>& models,
                    const std::vector<std::vector<double>>& data, const std::vector<double>& h);

// Δp (eq. 22) for one parameter; +inf when p_c = 0 and some p_j differs.
double uncertainty_index(const std::vector<double>& p_j, double p_c);
// Δp for every parameter of the model kind (name → Δp as a fraction; ×100 for the paper's %).
// A parameter identical everywhere (the paper's L = 4.9 s, printed "-") gets 0.
std::map<std::string, double> uncertainty_indices(const std::vector<Model>& per_recording,
                                                  const Model& nominal);

}  // namespace canalsim::reduced
