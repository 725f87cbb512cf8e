#include "reduced_models/identification.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <optional>
#include <utility>

#include "core/format.hpp"
#include "core/parallel.hpp"
#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced {

namespace detail {

void check_data_for_fit(ModelKind kind, const std::vector<const ExperimentData*>& data,
                        const FitOptions& options) {
  if (data.empty()) throw InputError("fit: no recordings given");
  if (const Status status = options.validate(); !status) throw InputError("fit options: " + status.message());
  // Each recording holds at least twice as many samples as the model has unknowns (its
  // parameters and the operating point): fewer fit anything, and the figures mean nothing.
  const std::size_t needed = 2 * (parameter_names(kind).size() + 1);
  for (const auto* d : data) {
    if (d->size() < needed) {
      throw InputError(d->source + ": " + std::to_string(d->size()) + " samples: too few to fit " + model_name(kind) +
                       " (" + std::to_string(parameter_names(kind).size()) + " parameters and the operating point): " +
                       "expected at least " + std::to_string(needed));
    }
    // The response is what follows the command's first move away from the operating point: a
    // move in the last samples leaves nothing to fit (K = 0 would "fit" perfectly).
    std::size_t first_move = 0;
    while (first_move < d->size() && std::abs(d->u_mm[first_move] - d->u0_mm) <= 1e-9 * std::max(1.0, std::abs(d->u0_mm))) {
      ++first_move;
    }
    if (d->size() - first_move < needed) {
      throw InputError(d->source + ": the command first leaves its operating point " + format_g(d->u0_mm) + " mm at t = " +
                       format_g(first_move < d->size() ? d->t_s[first_move] : d->t_s.back()) + " s, " +
                       std::to_string(d->size() - first_move) + " samples before the end: too few to fit " +
                       model_name(kind) + " (expected at least " + std::to_string(needed) + ")");
    }
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
                 const SimulationOptions& simulation, const std::vector<double>& offsets) {
  FitResult result;
  result.model = model;
  // SOPD's two lags commute: report the slower one as T (the canonical order T >= T2).
  if (model.kind == ModelKind::sopd && result.model.p.T2 > result.model.p.T) {
    std::swap(result.model.p.T, result.model.p.T2);
  }
  for (std::size_t j = 0; j < data.size(); ++j) {
    const ExperimentData* d = data[j];
    ExperimentData shifted;
    if (!offsets.empty() && offsets[j] != 0.0) {
      shifted = *d;
      shifted.y0_mm += offsets[j];
      d = &shifted;
    }
    const auto v = validate_model(model, *d, simulation);
    result.y0_mm.push_back(d->y0_mm);
    result.sources.push_back(d->source);
    result.iae.push_back(v.iae);
    result.nrmse.push_back(v.nrmse);
    result.response.push_back(v.response);
    result.iae_total += v.iae;
  }
  result.cost_total = result.iae_total;
  return result;
}

}  // namespace detail

namespace {

using namespace detail;

// A model nested in another: the outer model equals the inner one when `parameter` = `value`
// (LFOM at λ = 1 is LIOM; NLIOM at γ = 0 is LIOM; NLFOM at λ = 1 is NLIOM, at γ = 0 LFOM).
struct Nesting {
  ModelKind inner;
  const char* parameter;
  double value;
};

std::vector<Nesting> nested_models(ModelKind kind) {
  switch (kind) {
    case ModelKind::lfom: return {{ModelKind::liom, "lambda", 1.0}};
    case ModelKind::nliom_f:
    case ModelKind::nliom_s: return {{ModelKind::liom, "gamma", 0.0}};
    case ModelKind::nlfom_f: return {{ModelKind::nliom_f, "lambda", 1.0}, {ModelKind::lfom, "gamma", 0.0}};
    case ModelKind::nlfom_s: return {{ModelKind::nliom_s, "lambda", 1.0}, {ModelKind::lfom, "gamma", 0.0}};
    case ModelKind::idz: return {{ModelKind::id, "Tz", 0.0}};
    default: return {};
  }
}

// The nesting value lies in the parameter's bounds (or is its fixed value).
bool nesting_allowed(const Nesting& n, const FitOptions& options) {
  const auto& spec = options.bounds[n.parameter];
  if (spec.fixed) return *spec.initial == n.value;
  return spec.lower <= n.value && n.value <= spec.upper;
}

// Shortest run of samples over which the input holds (changes below 1 % of its range ignored),
// not counting the runs at the ends of the record.
std::size_t shortest_input_hold(const ExperimentData& d) {
  const auto [lo, hi] = std::minmax_element(d.u_mm.begin(), d.u_mm.end());
  const double threshold = 0.01 * (*hi - *lo);
  std::size_t shortest = d.size(), run_start = 0;
  bool first_run = true;
  for (std::size_t k = 1; k < d.size(); ++k) {
    if (std::abs(d.u_mm[k] - d.u_mm[k - 1]) <= threshold) continue;
    if (!first_run) shortest = std::min(shortest, k - run_start);
    first_run = false;
    run_start = k;
  }
  return shortest;
}

// Upper bounds left at +∞ ("from the data") made concrete: T and T2 up to ten times the longest
// recording, L up to half the shortest one. A parameter whose bounds leave one value is held
// there: the optimisers need lower < upper on every parameter they move.
FitOptions resolve_bounds(FitOptions options, const std::vector<const ExperimentData*>& data) {
  double longest = 0.0, shortest = kInf;
  for (const auto* d : data) {
    longest = std::max(longest, d->duration());
    shortest = std::min(shortest, d->duration());
  }
  auto& b = options.bounds;
  for (auto* spec : {&b.T, &b.T2, &b.Tz}) {
    if (std::isinf(spec->upper)) spec->upper = std::max(spec->lower, 10.0 * longest);
  }
  if (std::isinf(b.L.upper)) b.L.upper = std::max(b.L.lower, 0.5 * shortest);
  for (const char* name : {"K", "T", "T2", "lambda", "gamma", "L", "K_sub", "gamma_sub", "Tz"}) {
    ParameterSpec& spec = b[name];
    if (!spec.fixed && spec.lower == spec.upper) {
      spec.fixed = true;
      spec.initial = spec.lower;
    }
  }
  return options;
}

// One call of fit()/fit_nominal(): the recordings, a block-averaged copy of them for the searches
// when they are long, and the fits of every model searched so far (a model's fit is reused by
// the models that nest it).
class FitSession {
 public:
  FitSession(const std::vector<const ExperimentData*>& data, const FitOptions& options)
      : data_(data), options_(resolve_bounds(options, data)), search_options_(options_) {
    std::size_t longest = 0;
    for (const auto* d : data) longest = std::max(longest, d->size());
    const std::size_t limit = options.search_samples;
    if (limit == 0 || longest <= limit) {
      search_data_ = data_;
      return;
    }
    // The search runs on at most `search_samples` samples: block averages of `factor` samples
    // (the GL memory keeps its length in seconds), as many as the input allows without blurring
    // its fastest changes (a quarter of its shortest hold: a PRBS of 4-sample clock allows none,
    // a step test any), taken from the start of the record. A slow pool excited by steps is searched
    // over its whole record; a fast one driven by a PRBS on its leading part at full detail.
    std::size_t hold = longest;
    for (const auto* d : data) hold = std::min(hold, shortest_input_hold(*d));
    const std::size_t factor = std::clamp<std::size_t>(hold / 4, 1, (longest + limit - 1) / limit);
    for (const auto* d : data) {
      search_copies_.push_back(block_average(leading_samples(*d, limit * factor), factor));
    }
    for (const auto& d : search_copies_) search_data_.push_back(&d);
    // Bounds from the data: from the searched part (a leading segment's delay is at most half
    // of it), unless the caller set them.
    search_options_ = resolve_bounds(options, search_data_);
    auto& gl = search_options_.simulation.gl;
    gl.memory_terms = std::max<std::size_t>(1, gl.memory_terms / factor);
    // The search's delay is known to about one coarse sample: the polish on the recordings
    // brackets L within two of them.
    polish_bracket_s_ = 2.0 * search_copies_.front().h;
  }

  // The fit of `kind` on the recordings: the search's model, polished on the recordings when
  // the search ran on a copy, and never worse than a model it contains (below).
  const FitResult& fit(ModelKind kind) {
    if (const auto it = fits_.find(kind); it != fits_.end()) return it->second;
    const Searched& searched = search(kind);
    Model model = searched.model;
    bool converged = searched.converged;
    std::string message = searched.message;
    // A search on a copy is refined on the whole record by its own criterion, unless the
    // Gauss–Newton polish follows: it starts as well from the search's model.
    if (!search_copies_.empty() && !polished_by_gauss_newton(kind)) {
      stage(kind, "refining on the whole record");
      Problem whole(kind, data_, options_);
      double cost = 0.0;
      // Integer-order models simulate in O(n): their polish is one full-tolerance run with full
      // steps, which the flat valley between T and L of a slow, finely sampled pool needs (a
      // clean T = 60 s, L = 1.5 s step at 128 Hz: L 1.574 s with the short run, 1.530 s with
      // this); a fractional model's (O(nN) per evaluation) is one short local run.
      const bool cheap = !is_fractional(kind);
      model = whole.refine(model, cost, converged, message, cheap ? 1.0 : 0.1, 0,
                           polish_bracket_s_);
      count(whole);
    }
    const bool least_squares = polished_by_least_squares(kind);
    if (least_squares) stage(kind, "polishing by least squares");
    // A model fitted only to be compared with one that contains it is polished to a relative
    // 1e-6 (the comparison), and polished to the end only when it wins (below).
    const bool precise = nesting_depth_ == 0;
    FitResult r = least_squares ? polish_least_squares(kind, model, converged, message, precise)
                                : result(model, converged, message);
    // A model that contains another must not fit worse than it: the inner model's fit, written
    // as this model (λ = 1, γ = 0), is the same response, and replaces the fit if it is better.
    for (const auto& nesting : nested_models(kind)) {
      if (!nesting_allowed(nesting, options_)) continue;
      ++nesting_depth_;
      const FitResult& inner = fit(nesting.inner);
      --nesting_depth_;
      const Model outer = embed(kind, inner.model, nesting, data_, options_);
      FitResult embedded = least_squares ? least_squares_result(kind, outer, inner.converged, inner.message)
                                         : result(outer, inner.converged, inner.message);
      // The inner model polished to 1e-6 decides unless it comes within 1e-4 of winning (its
      // last iterations gain less than that): then it is polished to the end first.
      const bool loose_inner = least_squares && polished_by_gauss_newton(nesting.inner) && nesting_depth_ == 0;
      if (loose_inner && embedded.cost_total < r.cost_total * (1.0 + 1e-4)) {
        const FitResult inner_precise = polish_least_squares(nesting.inner, inner.model, inner.converged, inner.message, true);
        embedded = least_squares_result(kind, embed(kind, inner_precise.model, nesting, data_, options_),
                                        inner.converged, inner.message);
      }
      if (embedded.cost_total < r.cost_total) r = std::move(embedded);
    }
    return fits_.emplace(kind, std::move(r)).first->second;
  }

  int evaluations() const { return evaluations_; }
  int simulations() const { return simulations_; }

  // The std, correlations and inflation of the fit `r` of `kind` (fit_statistics.cpp), with the
  // output offsets and the sensor's mean reading that the least-squares polish fitted.
  void add_statistics(ModelKind kind, FitResult& r) const {
    add_fit_statistics(r, data_, options_, polished_by_least_squares(kind),
                       reading_bias_ ? &*reading_bias_ : nullptr);
  }

 private:
  // The polish profiles K out in closed form: a K held fixed keeps the IAE fit.
  bool polished_by_least_squares(ModelKind kind) const {
    return options_.criterion == Criterion::least_squares && output_linear_in_gain(kind) && !options_.bounds.K.fixed;
  }
  // The least-squares polish runs Levenberg–Marquardt (least_squares_polish.cpp) unless the
  // model quantises its output (eq. 17), whose cost has no derivative: NLopt polishes that.
  bool polished_by_gauss_newton(ModelKind kind) const {
    return polished_by_least_squares(kind) && options_.actuation.quantum_mm == 0.0;
  }

  struct Searched {
    Model model;
    double cost = kInf;
    bool converged = true;
    std::string message;
  };

  // Stages 1–3 on the search data: the delay search and refinement of a linear model, or the
  // coarse scans and refinement of a nonlinear one from its linear counterpart; then, for each
  // model this one contains, a refinement started from that model's optimum (λ = 1, γ = 0),
  // kept when it is better.
  const Searched& search(ModelKind kind) {
    if (const auto it = searched_.find(kind); it != searched_.end()) return it->second;
    stage(kind, "searching the delay and time constant");
    Searched best;
    Problem problem(kind, search_data_, search_options_);
    const ModelKind linear = linear_counterpart(kind);
    if (linear == kind) {
      // The delay that goes with the searched time constant is known to about 0.4 × the 4 %
      // step of the fine T pass: a bracket of ±T/10 (at least two samples) holds it.
      const Model start = problem.delay_search();
      const char* scale = dynamics_parameter(kind);
      const double T = scale ? get_parameter(start.p, scale) : 0.0;
      // No restart when the Gauss–Newton polish continues from here.
      best.model = problem.refine(start, best.cost, best.converged, best.message, 1.0,
                                  polished_by_gauss_newton(kind) ? 0 : -1,
                                  std::max(0.1 * T, 2.0 * search_data_.front()->h));
    } else {
      const Model start = nonlinear_start(problem, search(linear).model);
      best.model = problem.refine(problem.coarse_starts(start), best.cost, best.converged, best.message);
    }
    for (const auto& nesting : nested_models(kind)) {
      if (!nesting_allowed(nesting, options_)) continue;
      const Model start = embed(kind, search(nesting.inner).model, nesting, search_data_, search_options_);
      Searched candidate;
      candidate.model = problem.refine(start, candidate.cost, candidate.converged, candidate.message, 0.3, 0);
      if (candidate.cost < best.cost) best = std::move(candidate);
    }
    count(problem);
    return searched_.emplace(kind, std::move(best)).first->second;
  }

  // The inner model's parameters written as the outer model `kind` (head references of `kind`).
  static Model embed(ModelKind kind, const Model& inner, const Nesting& nesting,
                     const std::vector<const ExperimentData*>& data, const FitOptions& options) {
    Model m{kind, {}, options.actuation};
    m.p.head_ref_mm = options.head_ref_mm;
    m.p.head_ref_sub_mm = options.head_ref_sub_mm;
    set_head_references(m, data);
    for (const auto& name : parameter_names(nesting.inner)) {
      set_parameter(m.p, name, get_parameter(inner.p, name));
    }
    set_parameter(m.p, nesting.parameter, nesting.value);
    return m;
  }

  // Start of a nonlinear model from its linear counterpart's fit (the head term is normalised by
  // the mean head, so K starts at the linear gain; γ at 0.5 unless given).
  Model nonlinear_start(Problem& problem, const Model& linear_fit) const {
    Model start = problem.base();
    start.p.T = linear_fit.p.T;
    start.p.lambda = linear_fit.p.lambda;
    start.p.L = linear_fit.p.L;
    for (const auto& name : problem.free_names()) {
      const auto& spec = options_.bounds[name];
      double value = get_parameter(start.p, name);
      if (name == "K" || name == "K_sub") value = spec.initial.value_or(linear_fit.p.K);
      if (name == "gamma" || name == "gamma_sub") value = spec.initial.value_or(0.5);
      if ((name == "T" || name == "lambda" || name == "L") && spec.initial && !spec.fixed) {
        value = get_parameter(linear_fit.p, name);
      }
      set_parameter(start.p, name, std::clamp(value, spec.lower, spec.upper));
    }
    return start;
  }

  // The least-squares polish (Criterion::least_squares) of an IAE fit on the recordings: a local
  // run with K and the output offsets fitted with the other parameters, L within
  // ±max(2 samples, T/10), on a quantising sensor's mean reading where that matters.
  FitResult polish_least_squares(ModelKind kind, const Model& start, bool converged,
                                 const std::string& message, bool precise) {
    // NLopt's tolerances far below the default: the cost is the noise floor n σ² plus the
    // misfit, and what separates the optimum from its neighbourhood is a change of about σ², a
    // relative 1/n (1e-5 for 10⁵ samples) that ftol_rel = 1e-4 would stop short of (measured:
    // the delay of a T = 60 s pool at 100 Hz twice as scattered as the Cramér–Rao bound).
    FitOptions polish = options_;
    polish.relative_tolerance = 1e-10;
    Problem problem(kind, data_, polish);
    problem.use_least_squares();
    const char* scale = dynamics_parameter(kind);
    const double T = scale ? get_parameter(start.p, scale) : 0.0;
    const double bracket = std::max(0.1 * T, 2.0 * data_.front()->h);
    double cost = 0.0;
    std::string polish_message;
    bool polish_converged = true;
    auto run = [&](const Model& from, double step_scale, bool precise) {
      return polished_by_gauss_newton(kind)
                 ? problem.least_squares_polish(from, bracket, precise, cost, polish_converged, polish_message)
                 : problem.refine(from, cost, polish_converged, polish_message, step_scale, 1, bracket);
    };
    // A quantising sensor: fit its mean reading (sensor_reading.hpp), with the noise σ that fits
    // best at the levels' optimum. The first polish of the session finds that optimum and sets
    // the sensor for all (a rough optimum where a sensor's lattice will be polished on again, on
    // the searched part of a long record: it only picks σ and starts the polish); the others fit
    // the mean reading from the start.
    const bool sensor_known = reading_bias_.has_value();
    if (sensor_known && reading_bias_->lattice().step > 0.0) problem.use_reading_bias(*reading_bias_);
    const bool rough = !sensor_known && recorded_lattice(data_).step > 0.0;
    Model best = rough && polished_by_gauss_newton(kind) && !search_copies_.empty()
                     ? levels_optimum_on_the_searched_part(kind, start)
                     : run(start, 0.3, precise && !rough);
    if (!sensor_known) {
      reading_bias_ = best_reading_bias(kind, best);
      if (reading_bias_->lattice().step > 0.0) problem.use_reading_bias(*reading_bias_);
      if (rough || reading_bias_->lattice().step > 0.0) best = run(best, 0.1, precise);
    }
    count(problem);
    return least_squares_result(kind, best, converged && polish_converged, message);
  }

  // The least-squares optimum of the levels on the search's copy of the recordings, from `start`.
  Model levels_optimum_on_the_searched_part(ModelKind kind, const Model& start) {
    Problem searched(kind, search_data_, search_options_);
    searched.use_least_squares();
    const char* scale = dynamics_parameter(kind);
    const double T = scale ? get_parameter(start.p, scale) : 0.0;
    double cost = 0.0;
    bool converged = true;
    std::string message;
    const Model best = searched.least_squares_polish(start, std::max(0.1 * T, 2.0 * search_data_.front()->h), false,
                                                     cost, converged, message);
    count(searched);
    return best;
  }

  // The recordings' lattice and the σ (on a grid of 0.05–0.7 steps) whose mean reading fits
  // `model` best, its gain and offsets those of the levels. None (step 0) when the levels lie on
  // no lattice, when the model quantises, or when the misfit dwarfs the lattice: an RMS residual
  // above one step is not the quantiser's (its mean reading's bias is at most half a step), and
  // the bias would only roughen the cost.
  ReadingBias best_reading_bias(ModelKind kind, const Model& model) const {
    if (options_.actuation.quantum_mm > 0.0) return {};
    const SensorLattice lattice = recorded_lattice(data_);
    if (lattice.step == 0.0) return {};
    Problem problem(kind, data_, options_);
    problem.use_least_squares();
    Model m = model;
    const double level_cost = problem.cost(m);  // h Σ e², with K and the offsets fitted
    double duration = 0.0;
    for (const auto* d : data_) duration += d->h * static_cast<double>(d->size());
    if (!(std::sqrt(level_cost / duration) <= lattice.step)) return {};
    std::vector<std::vector<double>> g;
    problem.unit_responses(m, g);
    ReadingBias best;
    double best_cost = kInf;
    for (double ratio : {0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.7}) {
      const ReadingBias candidate(lattice, ratio * lattice.step);
      problem.use_reading_bias(candidate);
      const double c = problem.squared_error(m, g);  // at the levels' gain and offsets
      if (c < best_cost) {
        best_cost = c;
        best = candidate;
      }
    }
    return best;
  }

  // The fit result of `model` with its least-squares gain and output offsets.
  FitResult least_squares_result(ModelKind kind, const Model& model, bool converged,
                                 const std::string& message) const {
    Problem problem(kind, data_, options_);
    problem.use_least_squares();
    if (reading_bias_ && reading_bias_->lattice().step > 0.0) problem.use_reading_bias(*reading_bias_);
    Model m = model;
    const double cost = problem.cost(m);
    FitResult r = finish(m, data_, options_.simulation, problem.offsets());
    r.cost_total = cost;
    r.converged = converged;
    r.message = message;
    return r;
  }

  FitResult result(const Model& model, bool converged, const std::string& message) const {
    FitResult r = finish(model, data_, options_.simulation);
    r.converged = converged;
    r.message = message;
    return r;
  }

  void count(const Problem& problem) {
    evaluations_ += problem.evaluations();
    simulations_ += problem.simulations();
  }

  std::vector<const ExperimentData*> data_;
  // What a single long fit is doing (the models it nests are fitted first): options.progress,
  // with no share done, since the stages' costs differ by model and record.
  void stage(ModelKind kind, const std::string& what) const {
    if (options_.progress) options_.progress({-1.0, model_name(kind) + ": " + what});
  }

  FitOptions options_;
  FitOptions search_options_;
  std::vector<ExperimentData> search_copies_;
  std::vector<const ExperimentData*> search_data_;
  double polish_bracket_s_ = 0.0;
  int nesting_depth_ = 0;  // > 0 while fitting a model nested in the one asked for
  std::optional<ReadingBias> reading_bias_;  // the sensor of the least-squares polish, once set
  std::map<ModelKind, Searched> searched_;  // on the search data
  std::map<ModelKind, FitResult> fits_;     // on the recordings
  int evaluations_ = 0;
  int simulations_ = 0;
};

FitResult fit_impl(ModelKind kind, const std::vector<const ExperimentData*>& data,
                   const FitOptions& options) {
  check_data_for_fit(kind, data, options);
  FitSession session(data, options);
  FitResult r = session.fit(kind);
  session.add_statistics(kind, r);
  r.evaluations = session.evaluations();
  r.simulations = session.simulations();
  return r;
}

const char* const kNames[] = {"K", "T", "T2", "lambda", "gamma", "L", "K_sub", "gamma_sub", "Tz"};

}  // namespace


double estimate_fit_operations(ModelKind kind, const std::vector<ExperimentData>& data, const FitOptions& options,
                               double fits) {
  constexpr double kSimulationsPerFit = 300.0;
  double per_simulation = 0.0;
  for (const ExperimentData& d : data) {
    const auto n = static_cast<double>(d.size());
    const auto& gl = options.simulation.gl;
    const double terms = !is_fractional(kind)              ? 10.0
                         : gl.memory == GlMemory::full     ? 20.0 * std::pow(std::log2(std::max(n, 2.0)), 2.0)
                                                           : std::min(n, static_cast<double>(gl.memory_terms));
    per_simulation += n * terms;
  }
  return fits * kSimulationsPerFit * per_simulation;
}

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
  if (name == "Tz") return Tz;
  throw std::invalid_argument("unknown model parameter '" + name + "'");
}

namespace {

// One parameter's bounds, field `name`: finite (an upper +inf of T, T2, Tz or L stands for "from
// the data"), ordered, and holding the initial value (required when the parameter is fixed).
Status validate_bounds(const std::string& name, const ParameterSpec& s) {
  const bool upper_from_data = s.upper == kInf && (name == "T" || name == "T2" || name == "Tz" || name == "L");
  std::string range = "[";  // built by appending: GCC 12 warns (-Wrestrict) on "[" + std::string&&
  range += format_g(s.lower) + ", " + format_g(s.upper) + "]";
  return Validator()
      .require(std::isfinite(s.lower) && (std::isfinite(s.upper) || upper_from_data), name,
               "bounds must be finite (got " + range + ")")
      .require(s.lower <= s.upper, name,
               "lower " + format_g(s.lower) + " > upper " + format_g(s.upper) + " excludes every model")
      .require(!s.fixed || s.initial.has_value(), name, "fixed needs an initial value")
      .require(!s.initial || (*s.initial >= s.lower && *s.initial <= s.upper), name,
               "initial value " + format_g(s.initial.value_or(0.0)) + " lies outside " + range +
                   " (not clipped; widen the bounds)")
      .status();
}

}  // namespace

Status FitOptions::validate() const {
  Validator check;
  for (const char* name : kNames) check.nested("bounds", validate_bounds(name, bounds[name]));
  // Bounds that leave no admissible value (T, T2, Tz, L >= 0; lambda > 0).
  check.require(bounds.T.upper >= 0.0, "bounds.T",
                "upper " + format_g(bounds.T.upper) + " s < 0 excludes every model (T >= 0)");
  check.require(bounds.T2.upper >= 0.0, "bounds.T2",
                "upper " + format_g(bounds.T2.upper) + " s < 0 excludes every model (T2 >= 0)");
  check.require(bounds.L.upper >= 0.0, "bounds.L",
                "upper " + format_g(bounds.L.upper) + " s < 0 excludes every model (L >= 0)");
  check.require(bounds.lambda.upper > 0.0, "bounds.lambda",
                "upper " + format_g(bounds.lambda.upper) + " <= 0 excludes every model (lambda > 0)");
  check.require(bounds.T.lower >= 0.0, "bounds.T.lower", bounds.T.lower, ">= 0 s")
      .require(bounds.T2.lower >= 0.0, "bounds.T2.lower", bounds.T2.lower, ">= 0 s")
      .require(bounds.Tz.lower >= 0.0, "bounds.Tz.lower", bounds.Tz.lower, ">= 0 s")
      .require(bounds.L.lower >= 0.0, "bounds.L.lower", bounds.L.lower, ">= 0 s")
      .require(bounds.lambda.lower > 0.0, "bounds.lambda.lower", bounds.lambda.lower, "> 0");
  check.require(relative_tolerance > 0.0, "relative_tolerance", relative_tolerance, "> 0")
      .require(max_evaluations >= 1, "max_evaluations", max_evaluations, ">= 1")
      .require(restarts >= 0, "restarts", restarts, ">= 0")
      .require(nonlinear_restarts >= 0, "nonlinear_restarts", nonlinear_restarts, ">= 0")
      .require(hybrid_restarts >= 0, "hybrid_restarts", hybrid_restarts, ">= 0")
      .require(threads >= 1, "threads", threads, ">= 1")
      .require(head_ref_mm >= 0.0, "head_ref_mm", head_ref_mm, ">= 0 (0 = mean head of the data)")
      .require(head_ref_sub_mm >= 0.0, "head_ref_sub_mm", head_ref_sub_mm, ">= 0")
      .nested("actuation", actuation.validate())
      .nested("simulation", simulation.validate());
  return check.status();
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
  if (const Status status = options.validate(); !status) throw InputError("fit options: " + status.message());
  std::vector<FitResult> results(data.size());
  ProgressCounter progress(options.progress, data.size());
  // One report per finished fit; a single fit (one recording) reports its stages instead.
  FitOptions each = options;
  if (data.size() > 1) each.progress = nullptr;
  parallel_for(data.size(), static_cast<int>(options.threads), [&](std::size_t i) {
    std::exception_ptr error;
    try {
      results[i] = fit(kind, data[i], each);
    } catch (...) {
      error = std::current_exception();  // reported by parallel_for once every fit has run
    }
    progress.finished("fits (" + model_name(kind) + " to " + data[i].source + ")");
    if (error) std::rethrow_exception(error);
  });
  return results;
}

namespace detail {

FitResult refit_impl(const Model& start, const std::vector<const ExperimentData*>& ptrs,
                     const FitOptions& given_options, double step_scale, int restarts) {
  check_data_for_fit(start.kind, ptrs, given_options);
  const FitOptions options = resolve_bounds(given_options, ptrs);
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
  const auto ptrs = detail::pointers(data);
  FitResult r = detail::refit_impl(start, ptrs, options, 1.0, -1);
  detail::add_fit_statistics(r, ptrs, options, false, nullptr);  // an IAE refinement: no offsets
  return r;
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
