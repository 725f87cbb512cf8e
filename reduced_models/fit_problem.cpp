// Stages 2–3 of a fit (identification.hpp): the cost with K profiled out, the coarse scans of the
// exponents and gains, and the NLopt refinement inside a delay bracket.
#include "reduced_models/fit_problem.hpp"

#include <algorithm>
#include <cmath>
#include <nlopt.hpp>
#include <stdexcept>

#include "core/format.hpp"

namespace canalsim::reduced::detail {

bool output_linear_in_gain(ModelKind kind) {
  return is_linear_time_invariant(kind) || kind == ModelKind::nliom_f || kind == ModelKind::nlfom_f;
}

ModelKind linear_counterpart(ModelKind kind) {
  if (kind == ModelKind::sopd || is_integrating(kind)) return kind;
  return is_fractional(kind) ? ModelKind::lfom : ModelKind::liom;
}

std::vector<const ExperimentData*> pointers(const std::vector<ExperimentData>& data) {
  std::vector<const ExperimentData*> out;
  for (const auto& d : data) out.push_back(&d);
  return out;
}

std::vector<double> output_deviation(const ExperimentData& d) {
  std::vector<double> r(d.size());
  for (std::size_t k = 0; k < d.size(); ++k) r[k] = d.y_dwe_mm[k] - d.y0_mm;
  return r;
}

Problem::Problem(ModelKind kind, std::vector<const ExperimentData*> data,
                 const FitOptions& options)
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

double Problem::cost(Model& m) {
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
  std::vector<std::vector<double>> g;
  unit_responses(m, g);
  if (least_squares_) return least_squares_cost(m, g);
  values_.clear();
  weights_.clear();
  for (std::size_t j = 0; j < data_.size(); ++j) {
    const auto& d = *data_[j];
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

void Problem::unit_responses(const Model& m, std::vector<std::vector<double>>& g) {
  Model unit = m;
  unit.p.K = 1.0;
  unit.actuation.quantum_mm = 0.0;
  g.resize(data_.size());
  // Linear time-invariant models: a whole-sample delay commutes with the simulation and a
  // fractional one is a blend of two whole-sample delays (delay_interpolation_weight), so the
  // undelayed unit responses of the last few (T, λ, T2) are cached and only re-delayed when
  // just L changes (as in BOBYQA's initial design, line steps along L and the polish's
  // difference in L). SOPD's exact ZOH delay is no such blend: it is simulated every time (O(n)).
  const bool lti = is_linear_time_invariant(kind_) && kind_ != ModelKind::sopd;
  if (!lti) {
    for (std::size_t j = 0; j < data_.size(); ++j) {
      g[j] = simulate(unit, *data_[j], options_.simulation).y_dwe_mm;
      ++simulations_;
      for (double& v : g[j]) v -= data_[j]->y0_mm;
    }
    return;
  }
  const auto& undelayed = undelayed_unit_responses(unit);
  for (std::size_t j = 0; j < data_.size(); ++j) {
    const auto& d = *data_[j];
    const double delay = m.p.L / d.h, frac = delay - std::floor(delay);
    blended_delay(undelayed[j], delay, *delay_interpolation_weight(unit, d.h, frac), g[j]);
  }
}

const std::vector<std::vector<double>>& Problem::undelayed_unit_responses(const Model& unit) {
  const std::array<double, 4> key{unit.p.T, unit.p.lambda, unit.p.T2, unit.p.Tz};
  for (auto& entry : cache_) {
    if (entry.key == key) {
      entry.last_use = ++cache_clock_;
      return entry.responses;
    }
  }
  if (cache_.size() < kCacheEntries) cache_.emplace_back();
  auto& entry = *std::min_element(cache_.begin(), cache_.end(), [](const CacheEntry& a, const CacheEntry& b) {
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
  return entry.responses;
}

void Problem::use_least_squares() {
  if (!profile_K_) throw std::logic_error("least squares: only for models linear in K");
  least_squares_ = true;
}

double Problem::least_squares_cost(Model& m, const std::vector<std::vector<double>>& g) {
  linear_gain_and_offsets(m, g);
  const bool reading = bias_.lattice().step > 0.0 && m.actuation.quantum_mm == 0.0;
  if (reading) gauss_newton_gain_and_offsets(m, g);
  return squared_error(m, g);
}

// min over K and c_j of Σ_j h_j Σ_k (r_jk − c_j − K g_jk)²: c_j = mean_j(r − K g) and K from the
// centred sums, K = Σ_j h_j Σ (r − r̄_j)(g − ḡ_j) / Σ_j h_j Σ (g − ḡ_j)², clipped to its bounds.
void Problem::linear_gain_and_offsets(Model& m, const std::vector<std::vector<double>>& g) {
  double cross = 0.0, energy = 0.0;
  std::vector<double> mean_r(data_.size()), mean_g(data_.size());
  for (std::size_t j = 0; j < data_.size(); ++j) {
    const auto n = static_cast<double>(data_[j]->size());
    double sr = 0.0, sg = 0.0;
    for (std::size_t k = 0; k < data_[j]->size(); ++k) {
      sr += residual_[j][k];
      sg += g[j][k];
    }
    mean_r[j] = sr / n;
    mean_g[j] = sg / n;
    for (std::size_t k = 0; k < data_[j]->size(); ++k) {
      const double dg = g[j][k] - mean_g[j];
      cross += data_[j]->h * (residual_[j][k] - mean_r[j]) * dg;
      energy += data_[j]->h * dg * dg;
    }
  }
  const auto& spec = options_.bounds.K;
  m.p.K = std::clamp(energy > 0.0 ? cross / energy : 0.0, spec.lower, spec.upper);
  offsets_.assign(data_.size(), 0.0);
  for (std::size_t j = 0; j < data_.size(); ++j) offsets_[j] = mean_r[j] - m.p.K * mean_g[j];
}

double Problem::squared_error(const Model& m, const std::vector<std::vector<double>>& g) const {
  const double r = m.actuation.quantum_mm;
  const bool reading = bias_.lattice().step > 0.0 && r == 0.0;
  double total = 0.0, slope = 0.0;
  for (std::size_t j = 0; j < data_.size(); ++j) {
    const auto& d = *data_[j];
    double s = 0.0;
    for (std::size_t k = 0; k < d.size(); ++k) {
      const double mu = d.y0_mm + offsets_[j] + m.p.K * g[j][k];
      const double e = (reading ? mu + bias_(mu, slope) : quantise(mu, r)) - d.y_dwe_mm[k];
      s += e * e;
    }
    total += s * d.h;
  }
  return total;
}

// Gauss–Newton on (K, c_1 … c_J) for the mean reading μ + b(μ), μ = y0_j + c_j + K g: the normal
// equations are an arrowhead (each c_j only in its recording), solved by the Schur complement.
void Problem::gauss_newton_gain_and_offsets(Model& m, const std::vector<std::vector<double>>& g) {
  const auto& spec = options_.bounds.K;
  const std::size_t J = data_.size();
  std::vector<double> a_kc(J), a_cc(J), b_c(J);
  double slope = 0.0;
  for (int iteration = 0; iteration < 3; ++iteration) {
    double a_kk = 0.0, b_k = 0.0;
    for (std::size_t j = 0; j < J; ++j) {
      const auto& d = *data_[j];
      a_kc[j] = a_cc[j] = b_c[j] = 0.0;
      for (std::size_t k = 0; k < d.size(); ++k) {
        const double mu = d.y0_mm + offsets_[j] + m.p.K * g[j][k];
        const double e = d.y_dwe_mm[k] - mu - bias_(mu, slope);
        const double jc = 1.0 + slope, jk = jc * g[j][k];
        a_kk += d.h * jk * jk;
        a_kc[j] += d.h * jk * jc;
        a_cc[j] += d.h * jc * jc;
        b_k += d.h * jk * e;
        b_c[j] += d.h * jc * e;
      }
    }
    double schur = a_kk, rhs = b_k;
    for (std::size_t j = 0; j < J; ++j) {
      if (!(a_cc[j] > 0.0)) return;
      schur -= a_kc[j] * a_kc[j] / a_cc[j];
      rhs -= a_kc[j] * b_c[j] / a_cc[j];
    }
    const double K_new = std::clamp(m.p.K + (schur > 0.0 ? rhs / schur : 0.0), spec.lower, spec.upper);
    const double dK = K_new - m.p.K;
    m.p.K = K_new;
    for (std::size_t j = 0; j < J; ++j) offsets_[j] += (b_c[j] - a_kc[j] * dK) / a_cc[j];
  }
}

Model Problem::coarse_starts(const Model& start) {
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

Model Problem::refine(const Model& start, double& best_cost, bool& converged,
                      std::string& message, double step_scale, int restarts, double bracket_s) {
  step_scale_ = step_scale;
  Model current = start;
  best_cost = kInf;
  const auto& Lspec = options_.bounds.L;
  const double h0 = data_.front()->h;
  double L_lo = Lspec.lower, L_hi = Lspec.upper;
  auto set_bracket = [&](double L) {
    const double half_width = bracket_s > 0.0 ? bracket_s : 2.0 * h0;
    L_lo = std::max(Lspec.lower, L - half_width);
    L_hi = std::min(Lspec.upper, L + half_width);
  };
  set_bracket(start.p.L);
  const int configured = kind_ == ModelKind::hybrid     ? options_.hybrid_restarts
                         : uses_gamma(kind_)            ? options_.nonlinear_restarts
                                                        : options_.restarts;
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

Model Problem::run_nlopt(const Model& start, double L_lo, double L_hi, bool alternate,
                         double& best_cost, bool& converged, std::string& message) {
  const std::size_t dim = free_.size();
  Model best = start;
  best_cost = kInf;
  // NLopt only ever sees a finite cost: a model that overflows (an unstable lag, a gain of 1e300
  // against levels of 1e-300) costs a penalty above the start's, not an inf or NaN that corrupts
  // BOBYQA's quadratic model.
  double penalty = kInf;
  auto evaluate = [&](const std::vector<double>& x) {
    Model m = base_;
    m.p.K = start.p.K;
    for (std::size_t i = 0; i < dim; ++i) set_parameter(m.p, free_[i], x[i]);
    const double c = cost(m);
    if (!std::isfinite(c)) return penalty;
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
    // L: a quarter of the bracket, at least half a sample (a slow pool's delay trades off against
    // its time constant along a long valley that steps of a sample only crawl along).
    // Others: a quarter of their value (relative: bounds from the data may span decades), or 2 %
    // of the bounds' width for a parameter at 0.
    double s = name == "L" ? std::max(0.5 * data_.front()->h, 0.125 * width)
                           : (x[i] != 0.0 ? 0.25 * std::abs(x[i]) : 0.02 * width);
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
  if (!std::isfinite(best_cost)) {
    converged = false;
    message = "the cost is not finite at the start (the recordings are degenerate or out of range for this model)";
    return best;
  }
  penalty = 10.0 * std::max(best_cost, 1.0);
  for (std::size_t i = 0; i < dim; ++i) {
    if (!(lo[i] < hi[i]) || !std::isfinite(x[i]) || !std::isfinite(step[i])) {
      converged = false;
      message = "parameter " + free_[i] + ": bounds [" + format_g(lo[i]) + ", " + format_g(hi[i]) +
                "] leave nothing to search";
      return best;
    }
  }
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

}  // namespace canalsim::reduced::detail
