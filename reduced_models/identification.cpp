#include "reduced_models/identification.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <nlopt.hpp>
#include <sstream>
#include <thread>

namespace canalsim::reduced {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// Models whose output deviation is K times a response that does not depend on K (the forcing
// does not read the model's own output): K can be profiled out exactly.
bool output_linear_in_gain(ModelKind kind) {
  return is_linear_time_invariant(kind) || kind == ModelKind::nliom_f || kind == ModelKind::nlfom_f;
}

ModelKind linear_counterpart(ModelKind kind) {
  if (kind == ModelKind::sopd) return ModelKind::sopd;
  return is_fractional(kind) ? ModelKind::lfom : ModelKind::liom;
}

std::vector<const ExperimentData*> pointers(const std::vector<ExperimentData>& data) {
  std::vector<const ExperimentData*> out;
  for (const auto& d : data) out.push_back(&d);
  return out;
}

// Deviation of the recorded output from the operating point.
std::vector<double> output_deviation(const ExperimentData& d) {
  std::vector<double> r(d.size());
  for (std::size_t k = 0; k < d.size(); ++k) r[k] = d.y_dwe_mm[k] - d.y0_mm;
  return r;
}

// One optimisation problem: a model kind, its data, which parameters NLopt moves, and whether
// K is profiled out (linear models).
class Problem {
 public:
  Problem(ModelKind kind, std::vector<const ExperimentData*> data, const FitOptions& options)
      : kind_(kind), data_(std::move(data)), options_(options) {
    base_.kind = kind;
    base_.actuation = options.actuation;
    base_.p.head_ref_mm = options.head_ref_mm;
    base_.p.head_ref_sub_mm = options.head_ref_sub_mm;
    set_head_references(base_, data_);
    for (const auto& d : data_) residual_.push_back(output_deviation(*d));
    for (const auto& name : parameter_names(kind)) {
      const auto& spec = options.bounds[name];
      if (spec.fixed) {
        set_parameter(base_.p, name, *spec.initial);
        continue;
      }
      if (name == "K" && output_linear_in_gain(kind)) {
        profile_K_ = true;
        continue;
      }
      free_.push_back(name);
    }
  }

  const std::vector<std::string>& free_names() const { return free_; }
  Model& base() { return base_; }
  int evaluations() const { return evaluations_; }
  int simulations() const { return simulations_; }

  // Cost (IAE or IAE_c) of the model `m`; with K profiled, m.p.K is set to the optimal gain.
  double cost(Model& m) {
    ++evaluations_;
    if (!profile_K_) {
      double total = 0.0;
      for (std::size_t j = 0; j < data_.size(); ++j) {
        const auto y = simulate(m, *data_[j], options_.simulation).y_dwe_mm;
        ++simulations_;
        total += iae(y, data_[j]->y_dwe_mm, data_[j]->h);
      }
      return total;
    }
    Model unit = m;
    unit.p.K = 1.0;
    unit.actuation.quantum_mm = 0.0;
    std::vector<std::vector<double>> g(data_.size());
    values_.clear();
    weights_.clear();
    // Linear time-invariant models: the GL recursion and the interpolating delay commute, so the
    // undelayed unit responses of the last few (T, λ, T2) are cached and only re-delayed when
    // just L changes (as in BOBYQA's initial design and line steps along L).
    const bool lti = is_linear_time_invariant(kind_);
    const std::vector<std::vector<double>>* undelayed_responses = nullptr;
    if (lti) {
      const std::array<double, 3> key{m.p.T, m.p.lambda, m.p.T2};
      for (auto& entry : cache_) {
        if (entry.key == key) {
          entry.last_use = ++cache_clock_;
          undelayed_responses = &entry.responses;
        }
      }
      if (!undelayed_responses) {
        if (cache_.size() < kCacheEntries) cache_.emplace_back();
        auto& entry = *std::min_element(cache_.begin(), cache_.end(),
                                        [](const CacheEntry& a, const CacheEntry& b) {
                                          return a.last_use < b.last_use;
                                        });
        Model undelayed = unit;
        undelayed.p.L = 0.0;
        entry.key = key;
        entry.last_use = ++cache_clock_;
        entry.responses.resize(data_.size());
        for (std::size_t j = 0; j < data_.size(); ++j) {
          entry.responses[j] = simulate(undelayed, *data_[j], options_.simulation).y_dwe_mm;
          ++simulations_;
          for (double& v : entry.responses[j]) v -= data_[j]->y0_mm;
        }
        undelayed_responses = &entry.responses;
      }
    }
    for (std::size_t j = 0; j < data_.size(); ++j) {
      const auto& d = *data_[j];
      if (lti) {
        fractional_delay((*undelayed_responses)[j], m.p.L / d.h, g[j]);
      } else {
        g[j] = simulate(unit, d, options_.simulation).y_dwe_mm;
        ++simulations_;
        for (double& v : g[j]) v -= d.y0_mm;
      }
      for (std::size_t k = 0; k < d.size(); ++k) {
        if (g[j][k] != 0.0) {
          values_.push_back(residual_[j][k] / g[j][k]);
          weights_.push_back(d.h * std::abs(g[j][k]));
        }
      }
    }
    const auto& spec = options_.bounds.K;
    const double K = values_.empty() ? 0.0 : weighted_median(values_, weights_);
    m.p.K = std::clamp(K, spec.lower, spec.upper);
    const double r = m.actuation.quantum_mm;
    double total = 0.0;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      const auto& d = *data_[j];
      double s = 0.0;
      for (std::size_t k = 0; k < d.size(); ++k) {
        s += std::abs(quantise(d.y0_mm + m.p.K * g[j][k], r) - d.y_dwe_mm[k]);
      }
      total += s * d.h;
    }
    return total;
  }

  // Delay grid (stage 1) for a linear model: returns the start with the best whole-sample shift.
  Model delay_grid() {
    std::vector<double> Ts, lambdas{1.0};
    const auto& Tspec = options_.bounds.T;
    if (Tspec.fixed) Ts = {*Tspec.initial};
    else if (Tspec.initial) Ts = {*Tspec.initial};
    else for (double T : {0.3, 1.0, 3.0}) Ts.push_back(std::clamp(T, Tspec.lower, Tspec.upper));
    if (is_fractional(kind_)) {
      const auto& ls = options_.bounds.lambda;
      if (ls.fixed || ls.initial) lambdas = {*ls.initial};
      else lambdas = {std::clamp(0.5, ls.lower, ls.upper), std::clamp(0.9, ls.lower, ls.upper)};
    }
    const auto& Lspec = options_.bounds.L;
    const double h0 = data_.front()->h;
    Model best = base_;
    double best_cost = kInf;
    for (double T : Ts) {
      for (double lambda : lambdas) {
        Model m = base_;
        m.p.K = 1.0;
        m.p.T = T;
        m.p.lambda = lambda;
        if (kind_ == ModelKind::sopd) {
          const auto& t2 = options_.bounds.T2;
          m.p.T2 = t2.initial ? *t2.initial : std::clamp(T / 3.0, t2.lower, t2.upper);
        }
        m.p.L = Lspec.fixed ? *Lspec.initial : 0.0;
        m.actuation.quantum_mm = 0.0;
        std::vector<std::vector<double>> g;
        for (const auto* d : data_) {
          auto y = simulate(m, *d, options_.simulation).y_dwe_mm;
          ++simulations_;
          for (double& v : y) v -= d->y0_mm;
          g.push_back(std::move(y));
        }
        ++evaluations_;
        long first = static_cast<long>(std::ceil(Lspec.lower / h0 - 1e-9));
        long last = static_cast<long>(std::floor(Lspec.upper / h0 + 1e-9));
        if (Lspec.fixed) first = last = 0;
        for (long shift = first; shift <= last; ++shift) {
          double gr = 0.0, gg = 0.0;
          for (std::size_t j = 0; j < data_.size(); ++j) {
            const auto s = static_cast<std::size_t>(std::lround(static_cast<double>(shift) * h0 / data_[j]->h));
            const auto& gj = g[j];
            const auto& rj = residual_[j];
            for (std::size_t k = s; k < gj.size(); ++k) {
              gr += gj[k - s] * rj[k];
              gg += gj[k - s] * gj[k - s];
            }
          }
          if (gg == 0.0) continue;
          const double K = std::clamp(gr / gg, options_.bounds.K.lower, options_.bounds.K.upper);
          double total = 0.0;
          for (std::size_t j = 0; j < data_.size(); ++j) {
            const auto s = static_cast<std::size_t>(std::lround(static_cast<double>(shift) * h0 / data_[j]->h));
            const auto& gj = g[j];
            const auto& rj = residual_[j];
            double acc = 0.0;
            for (std::size_t k = 0; k < gj.size(); ++k) {
              acc += std::abs((k >= s ? K * gj[k - s] : 0.0) - rj[k]);
            }
            total += acc * data_[j]->h;
          }
          if (total < best_cost) {
            best_cost = total;
            best = m;
            best.p.K = K;
            best.p.L = Lspec.fixed ? *Lspec.initial : static_cast<double>(shift) * h0;
          }
        }
      }
    }
    best.actuation = base_.actuation;
    return best;
  }

  // Coarse scans before the local refinement (the IAE is multimodal in γ, and for the hybrid in
  // the split of the gain between the regimes): alternately scans the exponents (γ, γ_sub) on a
  // small grid and, for the hybrid, the gains (K, K_sub) as multiples of the start, keeping the
  // best. About 30–60 cost evaluations.
  Model coarse_starts(const Model& start) {
    const auto is_free = [&](const char* name) {
      return std::find(free_.begin(), free_.end(), name) != free_.end();
    };
    Model best = start;
    double best_cost = cost(best);
    auto try_model = [&](Model m) {
      const double c = cost(m);
      if (c < best_cost) {
        best_cost = c;
        best = m;
      }
    };
    auto values = [&](const char* name, const std::vector<double>& grid, double current) {
      if (!is_free(name)) return std::vector<double>{current};
      const auto& spec = options_.bounds[name];
      std::vector<double> out;
      for (double g : grid) {
        if (g >= spec.lower && g <= spec.upper) out.push_back(g);
      }
      return out.empty() ? std::vector<double>{current} : out;
    };
    const bool hybrid = kind_ == ModelKind::hybrid;
    const std::vector<double> gamma_grid =
        hybrid ? std::vector<double>{0.5, 1.5, 3.0, 6.0}
               : std::vector<double>{0.25, 0.75, 1.5, 2.5, 4.0, 6.0, 8.5};
    auto scan_gamma = [&] {
      const Model centre = best;
      for (double g : values("gamma", gamma_grid, centre.p.gamma)) {
        for (double gs : values("gamma_sub", gamma_grid, centre.p.gamma_sub)) {
          Model m = centre;
          m.p.gamma = g;
          m.p.gamma_sub = gs;
          try_model(m);
        }
      }
    };
    auto scan_gains = [&] {
      const Model centre = best;
      for (double a : {0.7, 1.0, 1.4}) {
        for (double b : {0.7, 1.0, 1.4}) {
          Model m = centre;
          if (is_free("K")) m.p.K = std::clamp(centre.p.K * a, options_.bounds.K.lower, options_.bounds.K.upper);
          if (is_free("K_sub")) {
            m.p.K_sub = std::clamp(centre.p.K_sub * b, options_.bounds.K_sub.lower, options_.bounds.K_sub.upper);
          }
          try_model(m);
        }
      }
    };
    if (!is_free("gamma") && !is_free("gamma_sub") && !hybrid) return best;
    if (hybrid) scan_gains();
    scan_gamma();
    if (hybrid) scan_gains();
    return best;
  }

  // Stage 2: NLopt from `start` with L bracketed around start.p.L. Returns the best model.
  // `step_scale` scales NLopt's initial steps (1 = a fresh search, < 1 = polishing a good start);
  // `restarts` < 0 takes the count from the options.
  Model refine(const Model& start, double& best_cost, bool& converged, std::string& message,
               double step_scale = 1.0, int restarts = -1) {
    step_scale_ = step_scale;
    Model current = start;
    best_cost = kInf;
    const auto& Lspec = options_.bounds.L;
    const double h0 = data_.front()->h;
    double L_lo = Lspec.lower, L_hi = Lspec.upper;
    auto set_bracket = [&](double L) {
      L_lo = std::max(Lspec.lower, L - 2.0 * h0);
      L_hi = std::min(Lspec.upper, L + 2.0 * h0);
    };
    set_bracket(start.p.L);
    const int configured = kind_ == ModelKind::hybrid ? options_.hybrid_restarts : options_.restarts;
    const int runs = 1 + std::max(0, restarts >= 0 ? restarts : configured);
    int recentre = 0;
    for (int run = 0; run < runs; ++run) {
      const Model before = current;
      double cost = kInf;
      // Restarts alternate the optimiser: BOBYQA's quadratic models can stall on this nonsmooth
      // (L1, switching) cost where a simplex method walks on, and vice versa.
      const bool alternate = run % 2 == 1;
      current = run_nlopt(current, L_lo, L_hi, alternate, cost, converged, message);
      if (cost < best_cost) best_cost = cost;
      const double L = current.p.L;
      const bool at_edge = (L - L_lo < 1e-6 * h0 && L_lo > Lspec.lower) ||
                           (L_hi - L < 1e-6 * h0 && L_hi < Lspec.upper);
      if (at_edge && recentre < 5 && !Lspec.fixed) {
        ++recentre;
        set_bracket(L);
        --run;  // the bracket moved: this run does not count as a restart
        continue;
      }
      bool same = true;
      for (const auto& name : free_) {
        same = same && get_parameter(before.p, name) == get_parameter(current.p, name);
      }
      if (same && run > 0) break;
    }
    return current;
  }

 private:
  Model run_nlopt(const Model& start, double L_lo, double L_hi, bool alternate, double& best_cost,
                  bool& converged, std::string& message) {
    const std::size_t dim = free_.size();
    Model best = start;
    best_cost = kInf;
    auto evaluate = [&](const std::vector<double>& x) {
      Model m = base_;
      m.p.K = start.p.K;
      for (std::size_t i = 0; i < dim; ++i) set_parameter(m.p, free_[i], x[i]);
      const double c = cost(m);
      if (c < best_cost) {
        best_cost = c;
        best = m;
      }
      return c;
    };
    if (dim == 0) {
      evaluate({});
      return best;
    }
    std::vector<double> lo(dim), hi(dim), x(dim), step(dim);
    for (std::size_t i = 0; i < dim; ++i) {
      const auto& name = free_[i];
      const auto& spec = options_.bounds[name];
      lo[i] = name == "L" ? L_lo : spec.lower;
      hi[i] = name == "L" ? L_hi : spec.upper;
      x[i] = std::clamp(get_parameter(start.p, name), lo[i], hi[i]);
      const double width = hi[i] - lo[i];
      double s = name == "L" ? 0.5 * data_.front()->h : std::max(0.1 * std::abs(x[i]), 0.02 * width);
      if (name == "gamma" || name == "gamma_sub") s = 0.2;
      if (name == "lambda") s = 0.05;
      s = std::min(s * step_scale_, 0.5 * width);
      // BOBYQA moves a start that lies closer than one step to a bound (onto the bound or one
      // step inside it), so the start itself might never be evaluated: keep the step within the
      // room the start has (a start on a bound is kept as it is).
      const double room = std::min(x[i] - lo[i], hi[i] - x[i]);
      if (room > 0.0) s = std::min(s, std::max(room, 1e-3 * width));
      step[i] = s > 0.0 ? s : 1e-6;
    }
    evaluate(x);  // the start: the search never returns a model worse than it
    nlopt::algorithm algorithm = nlopt::LN_BOBYQA;
    if (options_.optimizer == Optimizer::sbplx) algorithm = nlopt::LN_SBPLX;
    if (options_.optimizer == Optimizer::nelder_mead) algorithm = nlopt::LN_NELDERMEAD;
    if (alternate) algorithm = algorithm == nlopt::LN_BOBYQA ? nlopt::LN_SBPLX : nlopt::LN_BOBYQA;
    if (dim < 2) algorithm = nlopt::LN_NELDERMEAD;
    nlopt::opt opt(algorithm, static_cast<unsigned>(dim));
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    // A polish (step_scale < 1) starts within about a percent of the optimum: a tolerance ten
    // times looser (but not looser than 1e-3) is enough there.
    const double tolerance = step_scale_ < 1.0
                                 ? std::max(options_.relative_tolerance,
                                            std::min(1e-3, 10.0 * options_.relative_tolerance))
                                 : options_.relative_tolerance;
    opt.set_xtol_rel(tolerance);
    opt.set_ftol_rel(tolerance);
    opt.set_maxeval(options_.max_evaluations);
    opt.set_initial_step(step);
    struct Context {
      decltype(evaluate)* f;
    } context{&evaluate};
    opt.set_min_objective(
        [](const std::vector<double>& v, std::vector<double>&, void* data) {
          return (*static_cast<Context*>(data)->f)(v);
        },
        &context);
    double value = 0.0;
    try {
      const auto result = opt.optimize(x, value);
      converged = result != nlopt::MAXEVAL_REACHED && result != nlopt::MAXTIME_REACHED;
      message = result == nlopt::MAXEVAL_REACHED ? "stopped at max_evaluations" : "converged";
    } catch (const nlopt::roundoff_limited&) {
      message = "converged (roundoff-limited)";
    } catch (const std::exception& e) {
      converged = false;
      message = std::string("optimiser failed: ") + e.what();
    }
    return best;
  }

  ModelKind kind_;
  std::vector<const ExperimentData*> data_;
  const FitOptions& options_;
  Model base_;
  std::vector<std::vector<double>> residual_;
  std::vector<std::string> free_;
  bool profile_K_ = false;
  int evaluations_ = 0;
  int simulations_ = 0;  // model simulations (one per recording per evaluation, fewer if cached)
  double step_scale_ = 1.0;
  struct CacheEntry {
    std::array<double, 3> key{};                  // (T, λ, T2)
    std::vector<std::vector<double>> responses;   // undelayed unit responses per recording
    unsigned long last_use = 0;
  };
  static constexpr std::size_t kCacheEntries = 4;
  std::vector<CacheEntry> cache_;
  unsigned long cache_clock_ = 0;
  std::vector<double> values_, weights_;
};


void check_data_for_fit(ModelKind kind, const std::vector<const ExperimentData*>& data,
                        const FitOptions& options) {
  if (data.empty()) throw InputError("fit: no recordings given");
  if (const auto why = options.validate(); !why.empty()) throw InputError("fit options: " + why);
  for (const auto* d : data) {
    if (uses_upstream_level(kind)) require_upstream_level(*d, model_name(kind));
    const auto& L = options.bounds.L;
    if (L.lower >= d->duration()) {
      throw InputError(d->source + ": bounds.L: lower bound " + number(L.lower) +
                       " s is not shorter than the recording (" + number(d->duration()) +
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
      return field + ": bounds must be finite (got [" + number(s.lower) + ", " + number(s.upper) + "])";
    }
    if (s.lower > s.upper) {
      return field + ": lower " + number(s.lower) + " > upper " + number(s.upper) +
             " excludes every model";
    }
    if (s.fixed && !s.initial) return field + ": fixed needs an initial value";
    if (s.initial && !(*s.initial >= s.lower && *s.initial <= s.upper)) {
      return field + ": initial value " + number(*s.initial) + " lies outside [" +
             number(s.lower) + ", " + number(s.upper) + "] (not clipped; widen the bounds)";
    }
  }
  if (bounds.T.upper < 0.0) return "bounds.T: upper " + number(bounds.T.upper) + " s < 0 excludes every model (T >= 0)";
  if (bounds.T2.upper < 0.0) return "bounds.T2: upper " + number(bounds.T2.upper) + " s < 0 excludes every model (T2 >= 0)";
  if (bounds.L.upper < 0.0) return "bounds.L: upper " + number(bounds.L.upper) + " s < 0 excludes every model (L >= 0)";
  if (bounds.lambda.upper <= 0.0) {
    return "bounds.lambda: upper " + number(bounds.lambda.upper) + " <= 0 excludes every model (lambda > 0)";
  }
  if (bounds.T.lower < 0.0) return "bounds.T: lower " + number(bounds.T.lower) + " s, expected >= 0";
  if (bounds.T2.lower < 0.0) return "bounds.T2: lower " + number(bounds.T2.lower) + " s, expected >= 0";
  if (bounds.L.lower < 0.0) return "bounds.L: lower " + number(bounds.L.lower) + " s, expected >= 0";
  if (bounds.lambda.lower <= 0.0) return "bounds.lambda: lower " + number(bounds.lambda.lower) + ", expected > 0";
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
  return fit_impl(kind, pointers(data), options);
}

std::vector<FitResult> fit_each(ModelKind kind, const std::vector<ExperimentData>& data,
                                const FitOptions& options) {
  if (const auto why = options.validate(); !why.empty()) throw InputError("fit options: " + why);
  std::vector<FitResult> results(data.size());
  std::vector<std::exception_ptr> errors(data.size());
  std::atomic<std::size_t> next{0};
  std::mutex progress_mutex;
  std::size_t done = 0;
  auto worker = [&] {
    for (std::size_t i = next++; i < data.size(); i = next++) {
      try {
        results[i] = fit(kind, data[i], options);
      } catch (...) {
        errors[i] = std::current_exception();
      }
      if (options.progress) {
        std::lock_guard lock(progress_mutex);
        ++done;
        options.progress("fitted " + model_name(kind) + " to " + data[i].source + " (" +
                         std::to_string(done) + "/" + std::to_string(data.size()) + ")");
      }
    }
  };
  const unsigned n_threads = std::min<unsigned>(options.threads, static_cast<unsigned>(data.size()));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < n_threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  for (auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return results;
}

namespace {

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

}  // namespace

FitResult refit_from(const Model& start, const std::vector<ExperimentData>& data,
                     const FitOptions& options) {
  return refit_impl(start, pointers(data), options, 1.0, -1);
}

std::vector<double> GammaGrid::values() const {
  std::vector<double> out;
  const auto count = static_cast<std::size_t>(std::floor((last - first) / step + 1e-9)) + 1;
  for (std::size_t i = 0; i < count; ++i) out.push_back(first + static_cast<double>(i) * step);
  return out;
}

std::string GammaGrid::validate() const {
  if (!std::isfinite(first) || !std::isfinite(last) || !std::isfinite(step)) {
    return "gamma grid: first, last and step must be finite";
  }
  if (!(step > 0.0)) return "gamma grid: step " + number(step) + ", expected > 0";
  if (first > last) return "gamma grid: first " + number(first) + " > last " + number(last);
  if ((last - first) / step > 1e5) return "gamma grid: more than 100000 values";
  return "";
}

GammaGrid GammaGrid::parse(const std::string& text) {
  GammaGrid g;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> g.first >> c1 >> g.last >> c2 >> g.step) || c1 != ':' || c2 != ':' ||
      !(in >> std::ws).eof()) {
    throw InputError("--gamma '" + text + "': expected first:last:step, e.g. 0:10:0.05");
  }
  if (const auto why = g.validate(); !why.empty()) throw InputError("--gamma '" + text + "': " + why);
  return g;
}

GammaSweep gamma_sweep(ModelKind kind, const std::vector<ExperimentData>& data,
                       const FitOptions& options, const GammaGrid& grid) {
  if (!uses_gamma(kind)) {
    throw InputError("gamma sweep: model " + model_name(kind) + " has no gamma parameter");
  }
  if (const auto why = grid.validate(); !why.empty()) throw InputError(why);
  if (const auto why = options.validate(); !why.empty()) throw InputError("fit options: " + why);
  GammaSweep sweep;
  sweep.gamma = grid.values();
  const std::size_t n = sweep.gamma.size();
  sweep.nrmse.assign(n, 0.0);
  sweep.iae.assign(n, 0.0);
  std::vector<FitResult> fits(n);
  const unsigned threads = std::max(1u, std::min<unsigned>(options.threads, static_cast<unsigned>(n)));
  std::vector<std::exception_ptr> errors(threads);
  std::atomic<std::size_t> done{0};
  std::mutex progress_mutex;
  auto chunk = [&](unsigned t) {
    try {
      const std::size_t begin = n * t / threads, end = n * (t + 1) / threads;
      std::optional<Model> previous;
      for (std::size_t i = begin; i < end; ++i) {
        FitOptions o = options;
        o.threads = 1;
        o.bounds.gamma = {std::min(o.bounds.gamma.lower, sweep.gamma[i]),
                          std::max(o.bounds.gamma.upper, sweep.gamma[i]), sweep.gamma[i], true};
        if (kind == ModelKind::hybrid) o.bounds.gamma_sub = o.bounds.gamma;
        if (!previous) {
          fits[i] = fit_nominal(kind, data, o);
        } else {
          Model start = *previous;
          start.p.gamma = sweep.gamma[i];
          if (kind == ModelKind::hybrid) start.p.gamma_sub = sweep.gamma[i];
          // Neighbouring γ: polish the previous fit (small steps, one optimiser run).
          fits[i] = refit_impl(start, pointers(data), o, 0.2, 0);
        }
        previous = fits[i].model;
        const std::size_t count = ++done;
        if (options.progress) {
          std::lock_guard lock(progress_mutex);
          options.progress("gamma sweep " + model_name(kind) + ": " + std::to_string(count) + "/" +
                           std::to_string(n));
        }
      }
    } catch (...) {
      errors[t] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(chunk, t);
  chunk(0);
  for (auto& th : pool) th.join();
  for (auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  for (std::size_t i = 0; i < n; ++i) {
    double mean = 0.0;
    for (double v : fits[i].nrmse) mean += v;
    sweep.nrmse[i] = mean / static_cast<double>(fits[i].nrmse.size());
    sweep.iae[i] = fits[i].iae_total;
    if (sweep.nrmse[i] > sweep.nrmse[sweep.best]) sweep.best = i;
  }
  sweep.best_fit = fits[sweep.best];
  return sweep;
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
