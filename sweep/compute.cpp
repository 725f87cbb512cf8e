#include "sweep/compute.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/format.hpp"
#include "diagnosis/diagnose.hpp"
#include "linearize/linearize.hpp"
#include "reduced_models/identification.hpp"
#include "scenarios/simulate.hpp"
#include "sweep/table.hpp"

namespace canalsim::sweep {
namespace {

using reduced::ModelKind;

// ---- column names -----------------------------------------------------------------------------

// The unit suffix of a reduced model's parameter: gains in mm of level per mm of opening (per
// second for the integrators), times in s (a fractional model's T in s^λ), orders and exponents
// without one.
std::string parameter_unit(ModelKind kind, const std::string& name) {
  if (name == "K") return reduced::is_integrating(kind) ? "_mm_per_mm_s" : "_mm_per_mm";
  if (name == "K_sub") return "_mm_per_mm";
  if (name == "T" || name == "T2" || name == "Tz" || name == "L") return "_s";
  return "";
}

const std::vector<std::string> kSummaryColumns = {"y_dwe_mean_mm", "y_dwe_std_mm", "y_dwe_min_mm", "y_dwe_max_mm",
                                                  "q_mean_lps", "submerged_share"};
const std::vector<std::string> kLinearizeColumns = {"lin_static_gain_mm_per_mm", "lin_delay_s", "lin_lambda",
                                                    "lin_K_mm_per_mm", "lin_T_s", "lin_L_s", "lin_error_pct",
                                                    "lin_error_lambda1_pct"};
const std::vector<std::string> kDiagnosisColumns = {"diag_verdict", "diag_parameter", "diag_unit", "diag_value",
                                                    "diag_std"};

std::vector<std::string> fit_columns(ModelKind kind) {
  const std::string prefix = model_column_prefix(kind) + "_";
  std::vector<std::string> names;
  for (const auto& p : reduced::parameter_names(kind)) {
    names.push_back(prefix + p + parameter_unit(kind, p));
    names.push_back(prefix + p + "_std" + parameter_unit(kind, p));
  }
  names.push_back(prefix + "nrmse_pct");
  names.push_back(prefix + "iae_mm_s");
  return names;
}

// ---- the figures ------------------------------------------------------------------------------

// Mean, standard deviation and range of the level at the downstream end, the mean discharge
// through the controlled gate, and the share of samples in submerged flow (conditions 8/10).
std::vector<std::string> summary_cells(const Recording& r) {
  const auto& y = r.column(columns::level_downstream_end);
  const double n = static_cast<double>(y.size());
  double sum = 0.0;
  for (double v : y) sum += v;
  const double mean = sum / n;
  double squares = 0.0;
  for (double v : y) squares += (v - mean) * (v - mean);
  const auto [low, high] = std::minmax_element(y.begin(), y.end());
  double q = 0.0;
  for (double v : r.column(columns::discharge)) q += v;
  double submerged = 0.0;
  for (double v : r.column(columns::regime)) submerged += v == static_cast<double>(RegimeCode::submerged) ? 1.0 : 0.0;
  return {number_cell(mean), number_cell(std::sqrt(squares / n)), number_cell(*low), number_cell(*high),
          number_cell(q / n), number_cell(submerged / n)};
}

// The fit `canalsim fit` makes by default (the IAE fit polished by least squares), refused past
// the fit cost ceiling as the command refuses it.
std::vector<std::string> fit_cells(ModelKind kind, const reduced::ExperimentData& data) {
  reduced::FitOptions options;
  options.criterion = reduced::Criterion::least_squares;
  options.threads = 1;  // the sweep's parallelism is over cases
  const double operations = reduced::estimate_fit_operations(kind, {data}, options);
  if (operations > reduced::kMaxFitOperations) {
    throw InputError("fit of " + reduced::model_name(kind) + ": about " + format_g(operations, 3) +
                     " model operations, expected at most " + format_g(reduced::kMaxFitOperations, 3) +
                     " (a shorter duration_s)");
  }
  if (reduced::uses_upstream_level(kind)) reduced::require_upstream_level(data, reduced::model_name(kind));
  const reduced::FitResult fit = reduced::fit(kind, data, options);
  std::vector<std::string> cells;
  const auto names = reduced::parameter_names(kind);  // the columns' order, and the std's
  for (std::size_t j = 0; j < names.size(); ++j) {
    cells.push_back(number_cell(reduced::get_parameter(fit.model.p, names[j])));
    cells.push_back(number_cell(j < fit.std.size() ? fit.std[j] : std::nan("")));
  }
  cells.push_back(number_cell(fit.nrmse.front()));
  cells.push_back(number_cell(fit.iae.front()));
  return cells;
}

// The linearised pool at the experiment's operating point, gate opening to y_dwe (m/m, which is
// mm/mm), and the LFOM fitted to its response over the PRBS band (as `canalsim linearize`).
std::vector<std::string> linearize_cells(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment) {
  linearize::LinearizeOptions options;
  options.poles = 0;  // not reported: the dense eigen-solve would cost more than the response
  const linearize::FrequencyResponse r = linearize::linearize(scenario, experiment, options);
  std::vector<std::string> cells = {number_cell(r.static_gain), number_cell(r.delay_s)};
  if (!r.band_fit) {
    cells.resize(kLinearizeColumns.size());
    return cells;
  }
  const linearize::FractionalFit& f = *r.band_fit;
  for (double v : {f.order, f.gain, f.time, f.delay, 100.0 * f.rms_relative_error, 100.0 * f.integer_rms_relative_error}) {
    cells.push_back(number_cell(v));
  }
  return cells;
}

// The case's recording diagnosed against the base scenario: the verdict and its parameter.
std::vector<std::string> diagnosis_cells(const scenarios::Scenario& base, const Recording& recording) {
  diagnosis::DiagnoseOptions options;
  options.threads = 1;
  const diagnosis::Diagnosis d = diagnosis::diagnose(base, {recording}, options);
  if (!d.ok) throw std::runtime_error("diagnosis: " + d.message);
  if (d.explanation.empty()) return {d.verdict, "", "", "", ""};
  const diagnosis::ParameterEstimate& p = d.explanation.front().parameter;
  return {d.verdict, p.name, p.unit, number_cell(p.value), number_cell(p.std)};
}

}  // namespace

std::string model_column_prefix(ModelKind kind) {
  std::string name = reduced::model_name(kind);
  for (char& c : name) c = c == '-' ? '_' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

std::vector<std::string> computed_columns(const Computations& compute) {
  std::vector<std::string> names;
  const auto add = [&names](const std::vector<std::string>& more) { names.insert(names.end(), more.begin(), more.end()); };
  if (compute.summary) add(kSummaryColumns);
  for (const ModelKind kind : compute.fit) add(fit_columns(kind));
  if (compute.linearize) add(kLinearizeColumns);
  if (compute.diagnose) add(kDiagnosisColumns);
  return names;
}

Recording simulate_case(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment,
                        std::vector<std::string>* warnings) {
  scenarios::SimulateOptions options;
  options.require_steady_state = true;
  options.warning = [warnings](const std::string& w) {
    if (warnings) warnings->push_back(w);
  };
  Recording recording = scenarios::simulate(scenario, experiment, options);
  recording.source = experiment.name;
  if (const std::string overtopped = recording.meta("warning_overtopping"); !overtopped.empty() && warnings) {
    warnings->push_back("overtopping: " + overtopped);
  }
  return recording;
}

CaseFigures compute_case(const scenarios::Scenario& scenario, const scenarios::ExperimentSpec& experiment,
                         const scenarios::Scenario& base, const Computations& compute) {
  CaseFigures figures;
  const Recording recording = simulate_case(scenario, experiment, &figures.warnings);
  const auto add = [&figures](const std::vector<std::string>& more) {
    figures.cells.insert(figures.cells.end(), more.begin(), more.end());
  };
  if (compute.summary) add(summary_cells(recording));
  if (!compute.fit.empty()) {
    const reduced::ExperimentData data = reduced::prepare_data(recording);
    for (const ModelKind kind : compute.fit) add(fit_cells(kind, data));
  }
  if (compute.linearize) add(linearize_cells(scenario, experiment));
  if (compute.diagnose) add(diagnosis_cells(base, recording));
  return figures;
}

}  // namespace canalsim::sweep
