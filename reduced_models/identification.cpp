#include "reduced_models/identification.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <utility>

#include "core/format.hpp"
#include "core/parallel.hpp"
#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced {

namespace detail {

void check_data_for_fit(ModelKind kind, const std::vector<const ExperimentData*>& data,
                        const FitOptions& options) {
  if (data.empty()) throw InputError("fit: no recordings given");
  if (const auto why = options.validate(); !why.empty()) throw InputError("fit options: " + why);
  for (const auto* d : data) {
    if (uses_upstream_level(kind)) require_upstream_level(*d, model_name(kind));
    const auto& L = options.bounds.L;
    if (L.lower >= d->duration()) {
      throw InputError(d->source + ": bounds.L: lower bound " + format_g(L.lower) +
                       " s is not shorter than the recording (" + format_g(d->duration()) +
                       " s): every delay in the bounds hides the whole response");
    }
  }
}

FitResult finish(const Model& model, const std::vector<const ExperimentData*>& data,
                 const SimulationOptions& simulation) {
  FitResult result;
  result.model = model;
  // SOPD's two lags commute: report the slower one as T (the canonical order T >= T2).
  if (model.kind == ModelKind::sopd && result.model.p.T2 > result.model.p.T) {
    std::swap(result.model.p.T, result.model.p.T2);
  }
  for (const auto* d : data) {
    const auto v = validate_model(model, *d, simulation);
    result.sources.push_back(d->source);
    result.iae.push_back(v.iae);
    result.nrmse.push_back(v.nrmse);
    result.response.push_back(v.response);
    result.iae_total += v.iae;
  }
  return result;
}

}  // namespace detail

namespace {

using namespace detail;

// Stages 1–3 of a fit: the delay grid and refinement of the linear counterpart, then (for a
// nonlinear model) the coarse scans and refinement of the model itself.
FitResult fit_from_linear_stage(ModelKind kind, const std::vector<const ExperimentData*>& data,
                                const FitOptions& options) {
  double cost = 0.0;
  bool converged = true;
  std::string message;
  const ModelKind linear = linear_counterpart(kind);
  Problem lin(linear, data, options);
  const Model linear_fit = lin.refine(lin.delay_grid(), cost, converged, message);
  int evaluations = lin.evaluations();
  int simulations = lin.simulations();
  Model best = linear_fit;
  if (linear != kind) {
    Problem nl(kind, data, options);
    Model start = nl.base();
    start.p.T = linear_fit.p.T;
    start.p.lambda = linear_fit.p.lambda;
    start.p.L = linear_fit.p.L;
    for (const auto& name : nl.free_names()) {
      const auto& spec = options.bounds[name];
      double value = get_parameter(start.p, name);
      if (name == "K" || name == "K_sub") value = spec.initial.value_or(linear_fit.p.K);
      if (name == "gamma" || name == "gamma_sub") value = spec.initial.value_or(0.5);
      if ((name == "T" || name == "lambda" || name == "L") && spec.initial && !spec.fixed) {
        value = get_parameter(linear_fit.p, name);
      }
      set_parameter(start.p, name, std::clamp(value, spec.lower, spec.upper));
    }
    best = nl.refine(nl.coarse_starts(start), cost, converged, message);
    evaluations += nl.evaluations();
    simulations += nl.simulations();
  }
  FitResult r = finish(best, data, options.simulation);
  r.evaluations = evaluations;
  r.simulations = simulations;
  r.converged = converged;
  r.message = message;
  return r;
}

// Stages 1–3, and for a fractional model (LFOM, NLFOM-S/F) a second search: the model contains
// itself at λ = 1, where it is a first-order lag, so it is also fitted with λ fixed at 1 and
// refined from there with λ free; the better search is kept. The IAE is multimodal in λ (a
// quantised output makes it piecewise flat), and a search started from the linear fit alone can
// settle at a λ < 1 that fits worse than λ = 1 — a nested model must not fit worse than the model
// it contains.
FitResult fit_searching(ModelKind kind, const std::vector<const ExperimentData*>& data,
                        const FitOptions& options) {
  FitResult best = fit_from_linear_stage(kind, data, options);
  const auto& lambda = options.bounds.lambda;
  const bool nests_lambda_one = is_fractional(kind) && kind != ModelKind::hybrid && !lambda.fixed &&
                                lambda.lower <= 1.0 && 1.0 <= lambda.upper;
  if (!nests_lambda_one) return best;
  FitOptions at_one_options = options;
  at_one_options.bounds.lambda = {lambda.lower, lambda.upper, 1.0, true};
  const FitResult at_one = fit_from_linear_stage(kind, data, at_one_options);
  Problem problem(kind, data, options);
  Model current = best.model;
  const double current_cost = problem.cost(current);
  double cost = 0.0;
  bool converged = true;
  std::string message;
  const Model refined = problem.refine(at_one.model, cost, converged, message, 0.3, 0);
  const int evaluations = best.evaluations + at_one.evaluations + problem.evaluations();
  const int simulations = best.simulations + at_one.simulations + problem.simulations();
  if (cost < current_cost) {
    best = finish(refined, data, options.simulation);
    best.converged = converged;
    best.message = message;
  }
  best.evaluations = evaluations;
  best.simulations = simulations;
  return best;
}

// A fit. Long records are searched on their leading `coarse_samples` samples; the whole record
// then only polishes that fit (one short local run).
FitResult fit_impl(ModelKind kind, const std::vector<const ExperimentData*>& data,
                   const FitOptions& options) {
  check_data_for_fit(kind, data, options);
  std::size_t longest = 0;
  for (const auto* d : data) longest = std::max(longest, d->size());
  if (options.coarse_samples == 0 || longest <= 2 * options.coarse_samples) {
    return fit_searching(kind, data, options);
  }
  std::vector<ExperimentData> heads;
  for (const auto* d : data) heads.push_back(leading_samples(*d, options.coarse_samples));
  const FitResult head_fit = fit_searching(kind, pointers(heads), options);
  Problem whole(kind, data, options);
  double cost = 0.0;
  bool converged = true;
  std::string message;
  const Model polished = whole.refine(head_fit.model, cost, converged, message, 0.1, 0);
  FitResult r = finish(polished, data, options.simulation);
  r.evaluations = head_fit.evaluations + whole.evaluations();
  r.simulations = head_fit.simulations + whole.simulations();
  r.converged = converged;
  r.message = message;
  return r;
}

const char* const kNames[] = {"K", "T", "T2", "lambda", "gamma", "L", "K_sub", "gamma_sub"};

}  // namespace


ParameterSpec& FitBounds::operator[](const std::string& name) {
  return const_cast<ParameterSpec&>(std::as_const(*this)[name]);
}

const ParameterSpec& FitBounds::operator[](const std::string& name) const {
  if (name == "K") return K;
  if (name == "T") return T;
  if (name == "T2") return T2;
  if (name == "lambda") return lambda;
  if (name == "gamma") return gamma;
  if (name == "L") return L;
  if (name == "K_sub") return K_sub;
  if (name == "gamma_sub") return gamma_sub;
  throw std::invalid_argument("unknown model parameter '" + name + "'");
}

std::string FitOptions::validate() const {
  for (const char* name : kNames) {
    const auto& s = bounds[name];
    const std::string field = std::string("bounds.") + name;
    if (!std::isfinite(s.lower) || !std::isfinite(s.upper)) {
      return field + ": bounds must be finite (got [" + format_g(s.lower) + ", " + format_g(s.upper) + "])";
    }
    if (s.lower > s.upper) {
      return field + ": lower " + format_g(s.lower) + " > upper " + format_g(s.upper) +
             " excludes every model";
    }
    if (s.fixed && !s.initial) return field + ": fixed needs an initial value";
    if (s.initial && !(*s.initial >= s.lower && *s.initial <= s.upper)) {
      return field + ": initial value " + format_g(*s.initial) + " lies outside [" +
             format_g(s.lower) + ", " + format_g(s.upper) + "] (not clipped; widen the bounds)";
    }
  }
  if (bounds.T.upper < 0.0) return "bounds.T: upper " + format_g(bounds.T.upper) + " s < 0 excludes every model (T >= 0)";
  if (bounds.T2.upper < 0.0) return "bounds.T2: upper " + format_g(bounds.T2.upper) + " s < 0 excludes every model (T2 >= 0)";
  if (bounds.L.upper < 0.0) return "bounds.L: upper " + format_g(bounds.L.upper) + " s < 0 excludes every model (L >= 0)";
  if (bounds.lambda.upper <= 0.0) {
    return "bounds.lambda: upper " + format_g(bounds.lambda.upper) + " <= 0 excludes every model (lambda > 0)";
  }
  if (bounds.T.lower < 0.0) return "bounds.T: lower " + format_g(bounds.T.lower) + " s, expected >= 0";
  if (bounds.T2.lower < 0.0) return "bounds.T2: lower " + format_g(bounds.T2.lower) + " s, expected >= 0";
  if (bounds.L.lower < 0.0) return "bounds.L: lower " + format_g(bounds.L.lower) + " s, expected >= 0";
  if (bounds.lambda.lower <= 0.0) return "bounds.lambda: lower " + format_g(bounds.lambda.lower) + ", expected > 0";
  if (!(relative_tolerance > 0.0)) return "relative_tolerance: expected > 0";
  if (max_evaluations < 1) return "max_evaluations: expected >= 1";
  if (restarts < 0) return "restarts: expected >= 0";
  if (hybrid_restarts < 0) return "hybrid_restarts: expected >= 0";
  if (threads < 1) return "threads: expected >= 1";
  if (!(head_ref_mm >= 0.0)) return "head_ref_mm: expected >= 0 (0 = mean head of the data)";
  if (!(head_ref_sub_mm >= 0.0)) return "head_ref_sub_mm: expected >= 0";
  if (const auto why = actuation.validate(); !why.empty()) return why;
  return simulation.validate();
}

double weighted_median(std::vector<double>& values, std::vector<double>& weights) {
  const std::size_t n = values.size();
  if (n == 0 || weights.size() != n) throw std::invalid_argument("weighted_median: bad sizes");
  struct Item {
    double value, weight;
  };
  thread_local std::vector<Item> items;
  items.resize(n);
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    items[i] = {values[i], weights[i]};
    total += weights[i];
  }
  const double half = 0.5 * total;
  // Quickselect on the value, keeping the weight of everything left of the current range.
  std::size_t lo = 0, hi = n;
  double left = 0.0;
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    std::nth_element(items.begin() + static_cast<long>(lo), items.begin() + static_cast<long>(mid),
                     items.begin() + static_cast<long>(hi),
                     [](const Item& a, const Item& b) { return a.value < b.value; });
    double below = 0.0;
    for (std::size_t i = lo; i < mid; ++i) below += items[i].weight;
    if (left + below > half) {
      hi = mid;
    } else if (left + below + items[mid].weight >= half) {
      return items[mid].value;
    } else {
      left += below + items[mid].weight;
      lo = mid + 1;
    }
  }
  return items[lo < n ? lo : n - 1].value;
}

FitResult fit(ModelKind kind, const ExperimentData& data, const FitOptions& options) {
  return fit_impl(kind, {&data}, options);
}

FitResult fit_nominal(ModelKind kind, const std::vector<ExperimentData>& data,
                      const FitOptions& options) {
  return fit_impl(kind, detail::pointers(data), options);
}

std::vector<FitResult> fit_each(ModelKind kind, const std::vector<ExperimentData>& data,
                                const FitOptions& options) {
  if (const auto why = options.validate(); !why.empty()) throw InputError("fit options: " + why);
  std::vector<FitResult> results(data.size());
  std::mutex progress_mutex;  // the callback is called from one thread at a time
  std::size_t done = 0;
  parallel_for(data.size(), static_cast<int>(options.threads), [&](std::size_t i) {
    std::exception_ptr error;
    try {
      results[i] = fit(kind, data[i], options);
    } catch (...) {
      error = std::current_exception();  // reported by parallel_for once every fit has run
    }
    if (options.progress) {
      std::lock_guard lock(progress_mutex);
      ++done;
      options.progress({static_cast<double>(done) / static_cast<double>(data.size()),
                        "fitted " + model_name(kind) + " to " + data[i].source + " (" +
                            std::to_string(done) + "/" + std::to_string(data.size()) + ")"});
    }
    if (error) std::rethrow_exception(error);
  });
  return results;
}

namespace detail {

FitResult refit_impl(const Model& start, const std::vector<const ExperimentData*>& ptrs,
                     const FitOptions& options, double step_scale, int restarts) {
  check_data_for_fit(start.kind, ptrs, options);
  Problem problem(start.kind, ptrs, options);
  Model s = problem.base();
  for (const auto& name : problem.free_names()) {
    const auto& spec = options.bounds[name];
    set_parameter(s.p, name, std::clamp(get_parameter(start.p, name), spec.lower, spec.upper));
  }
  s.p.K = start.p.K;
  double cost = 0.0;
  bool converged = true;
  std::string message;
  const Model best = problem.refine(s, cost, converged, message, step_scale, restarts);
  FitResult r = finish(best, ptrs, options.simulation);
  r.evaluations = problem.evaluations();
  r.simulations = problem.simulations();
  r.converged = converged;
  r.message = message;
  return r;
}

}  // namespace detail

FitResult refit_from(const Model& start, const std::vector<ExperimentData>& data,
                     const FitOptions& options) {
  return detail::refit_impl(start, detail::pointers(data), options, 1.0, -1);
}

Validation validate_model(const Model& model, const ExperimentData& data,
                          const SimulationOptions& options) {
  Validation v;
  v.source = data.source;
  v.response = simulate(model, data, options).y_dwe_mm;
  v.iae = iae(v.response, data.y_dwe_mm, data.h);
  v.nrmse = nrmse_percent(v.response, data.y_dwe_mm);
  return v;
}

}  // namespace canalsim::reduced
