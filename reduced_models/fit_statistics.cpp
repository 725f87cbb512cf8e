// How sure a reduced-model fit is (identification.hpp, FitResult::std): the Jacobian of the
// output residuals at the fitted model by forward differences, and the covariance, standard
// deviations and correlations from core/statistics.hpp, as calibration reports them.
//
// The residuals are those of the least-squares criterion: the model's mean output minus the
// recording, every sample of every recording, weighted by sqrt(h) as the criterion h Σ e² weighs
// them (the sandwich is then the covariance of that weighted estimator). The model's mean output
// is its level without the quantiser of eq. 17 (which has no derivative, and whose mean is the
// level itself), or, when the polish fitted a quantising sensor's mean reading
// (sensor_reading.hpp), that reading. The operating points the least-squares criterion estimated
// are parameters of the Jacobian too (each moves its recording's output by one), nuisance
// parameters whose uncertainty widens the others' and that are not reported.
//
// The model is a discretisation: a fractional model's Grünwald–Letnikov sum is first-order in the
// time step for smooth levels, but the response to each switch of the command rises like t^λ,
// where the sum is only of order λ — an LFOM fitted at h = 0.13 s is biased against the
// continuous system (its delay about half a step early, K and T a few per cent low), far outside
// the noise's std. The numerical part of the uncertainty is measured as calibration measures its
// grid's: the model is computed again at half and at a quarter of the step (the command held, the
// same memory in time); the ratio of the two changes of its output gives the observed order p,
// and the Gauss–Newton shift δ of the optimum from h to h/2 (core optimum_shift) extrapolates
// (Richardson) to the converged estimate 2^p δ / (2^p − 1) away — 2δ for a first-order error.
// The std reported is the statistical and that numerical part combined (root sum of squares); an
// integer-order model, simulated exactly (zoh.hpp), has none.
#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

#include "core/statistics.hpp"
#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced::detail {
namespace {

// The parameters the fit moved: not fixed, and with bounds that leave more than one value.
std::vector<std::string> fitted_names(ModelKind kind, const FitOptions& options) {
  std::vector<std::string> out;
  for (const auto& name : parameter_names(kind)) {
    const ParameterSpec& spec = options.bounds[name];
    if (!spec.fixed && spec.lower < spec.upper) out.push_back(name);
  }
  return out;
}

// Difference step: 1e-4 of the parameter's scale.
double difference_step(const std::string& name, double value, double h) {
  return 1e-4 * difference_scale(name, value, h);
}

// The recording sampled `divisor` times as often, each sample held over its sub-steps: the same
// zero-order held command on a finer step.
ExperimentData finer_step(const ExperimentData& d, std::size_t divisor) {
  ExperimentData finer = d;
  finer.h = d.h / static_cast<double>(divisor);
  auto held = [divisor](const std::vector<double>& v) {
    std::vector<double> out;
    out.reserve(divisor * v.size());
    for (double x : v) out.insert(out.end(), divisor, x);
    return out;
  };
  finer.u_mm = held(d.u_mm);
  finer.y_dwe_mm = held(d.y_dwe_mm);
  finer.y_up_mm = held(d.y_up_mm);
  finer.x_up_mm = held(d.x_up_mm);
  finer.t_s = held(d.t_s);
  for (std::size_t k = 0; k < finer.t_s.size(); ++k) finer.t_s[k] += static_cast<double>(k % divisor) * finer.h;
  return finer;
}

// The recordings the statistics run on, with the operating points of the fit.
class MeanOutput {
 public:
  MeanOutput(const std::vector<const ExperimentData*>& data, const FitResult& r, const FitOptions& options,
             const ReadingBias* bias)
      : data_(data), y0_(r.y0_mm), simulation_(options.simulation), bias_(bias && bias->lattice().step > 0.0 ? bias : nullptr) {}

  // The model's level on every recording, one after another (the rows of the Jacobian).
  // The simulation takes the recording's own y0; the fit's operating point shifts the output,
  // which is exact for the models whose offsets the least-squares criterion fits (output
  // linear in K: the forcing does not read the model's level) and a no-op for the others.
  std::vector<double> operator()(const Model& model) const {
    Model level = model;
    level.actuation.quantum_mm = 0.0;
    std::vector<double> out;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      const auto y = simulate(level, *data_[j], simulation_).y_dwe_mm;
      const double shift = j < y0_.size() ? y0_[j] - data_[j]->y0_mm : 0.0;
      for (double v : y) out.push_back(v + shift);
    }
    return out;
  }

  // The model's level as output() gives it, computed at 1/`divisor` of the recordings' time step
  // and read at their sample times: the command held over the sub-steps, the short memory that
  // many times the terms (the same memory in time). With `leading`, on each recording's first
  // `leading` samples only (the simulation is causal: the same levels there).
  std::vector<double> at_finer_step(const Model& model, std::size_t divisor,
                                    std::size_t leading = std::numeric_limits<std::size_t>::max()) const {
    Model level = model;
    level.actuation.quantum_mm = 0.0;
    SimulationOptions finer = simulation_;
    finer.gl.memory_terms *= divisor;
    std::vector<double> out;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      const std::size_t rows = std::min(leading, data_[j]->size());
      const ExperimentData segment = rows < data_[j]->size() ? leading_samples(*data_[j], rows) : *data_[j];
      const auto y = simulate(level, finer_step(segment, divisor), finer).y_dwe_mm;
      const double shift = j < y0_.size() ? y0_[j] - data_[j]->y0_mm : 0.0;
      for (std::size_t k = 0; k < rows; ++k) out.push_back(y[divisor * k] + shift);
    }
    return out;
  }

  // The mean output for levels μ: μ, or the sensor's mean reading μ + b(μ).
  std::vector<double> readings(std::vector<double> mu) const {
    for (double& v : mu) v = reading(v);
    return mu;
  }

  // The fit's operating point of each row: the output of a model whose output is linear in K
  // is y0 + K g, so d(output)/dK = (output − y0) / K without another simulation.
  std::vector<double> operating_points() const {
    std::vector<double> out;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      out.insert(out.end(), data_[j]->size(), j < y0_.size() ? y0_[j] : data_[j]->y0_mm);
    }
    return out;
  }

  // d(mean output)/d(level) at a level: 1, or 1 + b'(μ) for the sensor's mean reading.
  double slope(double mu) const {
    double derivative = 0.0;
    if (bias_) (*bias_)(mu, derivative);
    return 1.0 + derivative;
  }

 private:
  double reading(double mu) const {  // μ + b(μ), or μ
    double derivative = 0.0;
    return bias_ ? mu + (*bias_)(mu, derivative) : mu;
  }

  const std::vector<const ExperimentData*>& data_;
  std::vector<double> y0_;
  SimulationOptions simulation_;
  const ReadingBias* bias_;
};

// The column of the Jacobian for `name`: the reading's slope at the level times the level's
// derivative (the chain rule: the sensor's mean reading curves on the scale of its lattice step,
// far faster than the level moves with a parameter), the latter by forward differences (backward
// where the step would cross the upper bound), whose O(step) error is far below a std at a step
// of 1e-4 of the parameter's scale; for K of a model whose output is linear in it, exactly
// (μ − y0)/K. `centre`: the levels μ at the fit.
std::vector<double> difference_column(const MeanOutput& output, const Model& model, const std::string& name,
                                      const ParameterSpec& spec, double h, const std::vector<double>& centre) {
  const double value = get_parameter(model.p, name);
  if (name == "K" && value != 0.0 && output_linear_in_gain(model.kind)) {
    const std::vector<double> y0 = output.operating_points();
    std::vector<double> column(centre.size());
    for (std::size_t i = 0; i < column.size(); ++i) column[i] = output.slope(centre[i]) * (centre[i] - y0[i]) / value;
    return column;
  }
  const double step = difference_step(name, value, h);
  const double moved = value + step <= spec.upper ? value + step : std::max(value - step, spec.lower);
  std::vector<double> column(centre.size(), 0.0);
  if (moved == value) return column;  // no room inside the bounds: the data cannot say
  Model m = model;
  set_parameter(m.p, name, moved);
  const std::vector<double> level = output(m);
  for (std::size_t i = 0; i < column.size(); ++i) {
    column[i] = output.slope(centre[i]) * (level[i] - centre[i]) / (moved - value);
  }
  return column;
}

// The Jacobian (row-major, rows weighted by sqrt(h)) of the mean output over the fitted
// parameters and, when fitted, each recording's output offset.
std::vector<double> output_jacobian(const MeanOutput& output, const FitResult& r,
                                    const std::vector<const ExperimentData*>& data, const FitOptions& options,
                                    const std::vector<std::string>& names, bool offsets_fitted,
                                    const std::vector<double>& centre, std::size_t& columns) {
  columns = names.size() + (offsets_fitted ? data.size() : 0);
  std::vector<double> J(centre.size() * columns, 0.0);
  for (std::size_t c = 0; c < names.size(); ++c) {
    const auto column = difference_column(output, r.model, names[c], options.bounds[names[c]], data.front()->h, centre);
    for (std::size_t i = 0; i < column.size(); ++i) J[i * columns + c] = column[i];
  }
  std::size_t row = 0;
  for (std::size_t j = 0; j < data.size(); ++j) {
    for (std::size_t k = 0; k < data[j]->size(); ++k, ++row) {
      const double weight = std::sqrt(data[j]->h);
      for (std::size_t c = 0; c < names.size(); ++c) J[row * columns + c] *= weight;
      if (offsets_fitted) J[row * columns + names.size() + j] = weight * output.slope(centre[row]);
    }
  }
  return J;
}

// The statistics of the fitted parameters written per name of the model: the fixed ones 0 (std)
// and NaN (correlations); the offsets (after the fitted parameters) left out.
void write_statistics(FitResult& r, const std::vector<std::string>& names, const LeastSquaresCovariance& c,
                      const std::vector<double>& numerical) {
  const std::vector<double> std = standard_deviations(c);
  const std::vector<std::vector<double>> correlation = correlations(c);
  r.parameter_names = parameter_names(r.model.kind);
  const std::size_t n = r.parameter_names.size();
  std::vector<std::size_t> column(n, n);  // the Jacobian column of each name; n: fixed
  for (std::size_t a = 0; a < n; ++a) {
    const auto it = std::find(names.begin(), names.end(), r.parameter_names[a]);
    if (it != names.end()) column[a] = static_cast<std::size_t>(it - names.begin());
  }
  r.std.assign(n, 0.0);
  r.numerical_std.assign(n, 0.0);
  r.correlation.assign(n, std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
  for (std::size_t a = 0; a < n; ++a) {
    if (column[a] == n) continue;
    r.numerical_std[a] = numerical[column[a]];
    r.std[a] = std::hypot(std[column[a]], numerical[column[a]]);
    for (std::size_t b = 0; b < n; ++b) {
      if (column[b] != n) r.correlation[a][b] = correlation[column[a]][column[b]];
    }
  }
  r.inflation = c.inflation;
}

// The numerical part of each fitted parameter's std: |δ| 2^p / (2^p − 1), δ the shift of the
// optimum were the model computed at half the time step, p the order observed from h/2 to h/4
// (within [λ-like 0.25, 2]; the header's Richardson argument). All zero when halving the step
// changes nothing (an exact simulation). The order is a property of the scheme and of how the
// command switches, not of the record's length: it is observed on each recording's first
// kOrderSamples samples, where the quarter step costs a sixteenth of a long record's.
constexpr std::size_t kOrderSamples = 2048;

std::vector<double> numerical_deviations(const MeanOutput& output, const Model& model, const std::vector<double>& J,
                                         std::size_t columns, const std::vector<double>& mean,
                                         const std::vector<const ExperimentData*>& data) {
  const std::vector<double> half = output.readings(output.at_finer_step(model, 2));
  std::vector<double> change(mean.size());
  double first = 0.0;          // |y(h/2) − y(h)|²
  double first_leading = 0.0;  // the same on the leading samples
  std::vector<double> half_leading;
  std::size_t row = 0;
  for (const ExperimentData* d : data) {
    for (std::size_t k = 0; k < d->size(); ++k, ++row) {
      change[row] = std::sqrt(d->h) * (half[row] - mean[row]);
      const double squared = (half[row] - mean[row]) * (half[row] - mean[row]);
      first += squared;
      if (k < kOrderSamples) {
        first_leading += squared;
        half_leading.push_back(half[row]);
      }
    }
  }
  std::vector<double> deviation(columns, 0.0);
  if (!(first > 0.0)) return deviation;
  // Leading samples where the step changes nothing (the command has not moved yet): the whole.
  if (!(first_leading > 0.0)) {
    first_leading = first;
    half_leading = half;
  }
  const std::size_t leading = half_leading.size() < half.size() ? kOrderSamples : half.size();
  const std::vector<double> quarter = output.readings(output.at_finer_step(model, 4, leading));
  double second = 0.0;  // |y(h/4) − y(h/2)|² on the leading samples
  for (std::size_t i = 0; i < quarter.size(); ++i) {
    second += (quarter[i] - half_leading[i]) * (quarter[i] - half_leading[i]);
  }
  const double order = second > 0.0 ? std::clamp(0.5 * std::log2(first_leading / second), 0.25, 2.0) : 2.0;
  const double to_converged = std::pow(2.0, order) / (std::pow(2.0, order) - 1.0);
  deviation = optimum_shift(J, change, columns);
  for (double& v : deviation) v = to_converged * std::abs(v);
  return deviation;
}

// The statistics of the fit `r` (add_fit_statistics guards it).
void statistics_of(FitResult& r, const std::vector<const ExperimentData*>& data, const FitOptions& options,
                   bool offsets_fitted, const ReadingBias* bias) {
  const MeanOutput output(data, r, options, bias);
  const std::vector<std::string> names = fitted_names(r.model.kind, options);
  const std::vector<double> centre = output(r.model);  // levels
  const std::vector<double> mean = output.readings(centre);

  // Residuals: weighted by sqrt(h) for the covariance, unweighted per recording for their
  // autocorrelation.
  std::vector<double> residuals(centre.size());
  std::vector<std::vector<double>> series(data.size());
  std::size_t row = 0;
  for (std::size_t j = 0; j < data.size(); ++j) {
    for (std::size_t k = 0; k < data[j]->size(); ++k, ++row) {
      series[j].push_back(mean[row] - data[j]->y_dwe_mm[k]);
      residuals[row] = std::sqrt(data[j]->h) * series[j].back();
    }
  }
  std::size_t columns = 0;
  const std::vector<double> J = output_jacobian(output, r, data, options, names, offsets_fitted, centre, columns);
  write_statistics(r, names, least_squares_covariance(J, columns, residuals, series),
                   numerical_deviations(output, r.model, J, columns, mean, data));
}

}  // namespace

double difference_scale(const std::string& name, double value, double h) {
  const bool time = name == "T" || name == "T2" || name == "Tz" || name == "L";
  const bool gain = name == "K" || name == "K_sub";
  return std::max(std::abs(value), time ? h : gain ? 1e-3 : 0.01);
}

void add_fit_statistics(FitResult& r, const std::vector<const ExperimentData*>& data, const FitOptions& options,
                        bool offsets_fitted, const ReadingBias* bias) {
  // A model the fit reached but that cannot be simulated a step away (parameters the simulation
  // refuses) keeps its fit: its statistics are left not computed (NaN), never an exception.
  try {
    statistics_of(r, data, options, offsets_fitted, bias);
  } catch (const std::exception&) {
    r.parameter_names = parameter_names(r.model.kind);
    const std::size_t n = r.parameter_names.size();
    r.std.assign(n, std::numeric_limits<double>::quiet_NaN());
    r.numerical_std.assign(n, std::numeric_limits<double>::quiet_NaN());
    r.correlation.assign(n, std::vector<double>(n, std::numeric_limits<double>::quiet_NaN()));
    r.inflation = std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace canalsim::reduced::detail
