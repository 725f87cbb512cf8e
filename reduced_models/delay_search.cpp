// Stage 1 of a fit (identification.hpp): the delay search of the linear counterpart model.
//
// The delay enters the models as a shift of the input, so the cost is flat in L between samples
// and multimodal across them, and it trades off against the time constant: a slow response can
// be mimicked by a faster lag with a longer delay. The search therefore profiles the cost over
// every whole-sample delay inside the L bounds, with the other parameters fitted at each delay:
//
//   for every candidate dynamics (T on a logarithmic grid spanning the T bounds up to three
//   times the recording, × λ ∈ {0.5, 0.75, 1} for the fractional models, T2 = T/3 for SOPD):
//     g = unit-gain, undelayed response (one simulation);
//     for every shift s:  K(s) = Σ r_k g_{k−s} / Σ g_{k−s}²   (least squares, clipped to the K
//                                                               bounds)
//                         SSE(s) = Σ r² − 2 K Σ r g + K² Σ g²
// The correlations Σ r_k g_{k−s} for all s at once are one FFT product (O(n log n) per candidate);
// Σ g² over the overlap is a prefix sum. A second pass steps T by 4 % between the coarse grid's
// neighbours of the best one. The best (dynamics, shift) pair is the start of the refinement
// (fit_problem.cpp), whose delay bracket is as wide as a tenth of that time constant. Nothing ties the delay to a fixed set of time
// constants or to a neighbourhood of an earlier guess, so a slow pool cannot trade its missing
// time constant for a long delay: the grid holds time constants of the slow pool at every delay.
#include <algorithm>
#include <cmath>
#include <complex>
#include <unsupported/Eigen/FFT>

#include "reduced_models/fit_problem.hpp"

namespace canalsim::reduced::detail {
namespace {

// The smallest transform length ≥ `minimum` that kissfft (Eigen's FFT backend) takes fast: a
// product of its radices 2, 3 and 5, and a multiple of 4, which its real-input path needs. A
// power of two alone can nearly double the length.
std::size_t fast_transform_length(std::size_t minimum) {
  std::size_t best = 4;
  while (best < minimum) best <<= 1;
  for (std::size_t fives = 1; fives < best; fives *= 5) {
    for (std::size_t threes = fives; threes < best; threes *= 3) {
      std::size_t length = 4 * threes;
      while (length < minimum) length <<= 1;
      best = std::min(best, length);
    }
  }
  return best;
}

// Σ_i g[i] r[i + s] for s = 0 … max_shift (cross-correlation by FFT). Zero-padded to at least
// n + max_shift + 1 points: a term g[i] r[i + s] with i + s past the record meets a padded zero
// before the transform's period wraps it onto the record, so no shift asked for is aliased.
class Correlator {
 public:
  Correlator(const std::vector<double>& r, std::size_t max_shift)
      : n_(r.size()), size_(fast_transform_length(n_ + max_shift + 1)) {
    std::vector<double> padded(size_, 0.0);
    std::copy(r.begin(), r.end(), padded.begin());
    fft_.fwd(spectrum_r_, padded);
  }

  const std::vector<double>& correlate(const std::vector<double>& g) {
    padded_.assign(size_, 0.0);
    std::copy(g.begin(), g.end(), padded_.begin());
    fft_.fwd(spectrum_g_, padded_);
    for (std::size_t i = 0; i < spectrum_g_.size(); ++i) {
      spectrum_g_[i] = std::conj(spectrum_g_[i]) * spectrum_r_[i];
    }
    fft_.inv(out_, spectrum_g_);
    out_.resize(n_);
    return out_;
  }

 private:
  std::size_t n_;
  std::size_t size_;
  Eigen::FFT<double> fft_;
  std::vector<std::complex<double>> spectrum_r_, spectrum_g_;
  std::vector<double> padded_, out_;
};

// Candidate values of a parameter: its fixed or initial value, else `grid` clipped to its bounds.
std::vector<double> candidates(const ParameterSpec& spec, const std::vector<double>& grid) {
  if (spec.fixed || spec.initial) return {*spec.initial};
  std::vector<double> out;
  for (double v : grid) {
    const double c = std::clamp(v, spec.lower, spec.upper);
    if (out.empty() || std::abs(c - out.back()) > 1e-12 * std::max(1.0, std::abs(c))) out.push_back(c);
  }
  return out;
}

// Time constants from the smallest the data resolve (a quarter sample, or the lower bound) to
// three times the longest recording (beyond that a lag is indistinguishable from an integrator),
// about seven per decade.
std::vector<double> time_constant_grid(const ParameterSpec& spec,
                                       const std::vector<const ExperimentData*>& data) {
  double h = data.front()->h, duration = 0.0;
  for (const auto* d : data) {
    h = std::min(h, d->h);
    duration = std::max(duration, d->duration());
  }
  const double lo = std::max(spec.lower, 0.25 * h);
  const double hi = std::max(lo, std::min(spec.upper, 3.0 * duration));
  std::vector<double> grid;
  if (spec.lower < lo) grid.push_back(spec.lower);
  for (double T = lo; T < hi * 1.0001; T *= 1.4) grid.push_back(T);
  if (grid.back() < hi) grid.push_back(hi);
  return grid;
}

}  // namespace

const char* dynamics_parameter(ModelKind kind) {
  if (kind == ModelKind::id) return nullptr;
  return kind == ModelKind::idz ? "Tz" : "T";
}

Model Problem::delay_search() {
  // The time scale searched: T (IDZ: its zero's Tz; ID has none, one candidate).
  const char* scale = dynamics_parameter(kind_);
  const auto& Tspec = options_.bounds[scale ? scale : "T"];
  const auto Ts = scale ? candidates(Tspec, time_constant_grid(Tspec, data_)) : std::vector<double>{1.0};
  const auto lambdas = is_fractional(kind_) ? candidates(options_.bounds.lambda, {0.5, 0.75, 1.0})
                                            : std::vector<double>{1.0};
  const auto& Lspec = options_.bounds.L;
  const auto& Kspec = options_.bounds.K;
  const double h0 = data_.front()->h;
  long first = static_cast<long>(std::ceil(Lspec.lower / h0 - 1e-9));
  long last = static_cast<long>(std::floor(Lspec.upper / h0 + 1e-9));
  if (Lspec.fixed) first = last = 0;  // the fixed delay is in the simulated response
  // Shift of recording j for a shift of `shift` samples of the first one.
  const auto shift_of = [&](long shift, std::size_t j) {
    return static_cast<std::size_t>(std::lround(static_cast<double>(shift) * h0 / data_[j]->h));
  };
  for (std::size_t j = 0; j < data_.size(); ++j) {
    last = std::min(last, static_cast<long>(std::floor(static_cast<double>(data_[j]->size() - 1) *
                                                       data_[j]->h / h0)));
  }
  last = std::max(last, first);
  std::vector<Correlator> correlators;
  double rr = 0.0;
  for (std::size_t j = 0; j < data_.size(); ++j) {
    correlators.emplace_back(residual_[j], std::min(shift_of(last, j), data_[j]->size()));
    for (double v : residual_[j]) rr += v * v * data_[j]->h;
  }

  Model best = base_;
  double best_sse = kInf;
  std::vector<std::vector<double>> gr(data_.size()), gg_prefix(data_.size());
  // Profiles one candidate dynamics over every shift; keeps the best (dynamics, shift).
  const auto try_dynamics = [&](double T, double lambda) {
    Model m = base_;
    m.p.K = 1.0;
    if (scale) set_parameter(m.p, scale, T);
    m.p.lambda = lambda;
    if (kind_ == ModelKind::sopd) {
      const auto& t2 = options_.bounds.T2;
      m.p.T2 = t2.initial ? *t2.initial : std::clamp(T / 3.0, t2.lower, t2.upper);
    }
    m.p.L = Lspec.fixed ? *Lspec.initial : 0.0;
    m.actuation.quantum_mm = 0.0;
    for (std::size_t j = 0; j < data_.size(); ++j) {
      const auto& d = *data_[j];
      auto g = simulate(m, d, options_.simulation).y_dwe_mm;
      ++simulations_;
      for (double& v : g) v -= d.y0_mm;
      gr[j] = correlators[j].correlate(g);
      // gg_prefix[j][i] = Σ_{k<i} g_k²: the energy of the response shifted by s inside the
      // record is gg_prefix[n − s].
      gg_prefix[j].assign(g.size() + 1, 0.0);
      for (std::size_t k = 0; k < g.size(); ++k) gg_prefix[j][k + 1] = gg_prefix[j][k] + g[k] * g[k];
    }
    ++evaluations_;
    for (long shift = first; shift <= last; ++shift) {
      double sum_gr = 0.0, sum_gg = 0.0;
      for (std::size_t j = 0; j < data_.size(); ++j) {
        const std::size_t s = shift_of(shift, j), n = data_[j]->size();
        if (s >= n) continue;
        sum_gr += gr[j][s] * data_[j]->h;
        sum_gg += gg_prefix[j][n - s] * data_[j]->h;
      }
      if (!(sum_gg > 0.0)) continue;
      const double K = std::clamp(sum_gr / sum_gg, Kspec.lower, Kspec.upper);
      const double sse = rr - 2.0 * K * sum_gr + K * K * sum_gg;
      if (sse < best_sse) {
        best_sse = sse;
        best = m;
        best.p.K = K;
        best.p.L = Lspec.fixed ? *Lspec.initial : static_cast<double>(shift) * h0;
      }
    }
  };
  // The order nearest 1 over the whole T grid first (λ = 1 is a cheap recursion); the other orders
  // only within a factor of ten of the time constant found there.
  const auto first_order = std::min_element(lambdas.begin(), lambdas.end(), [](double a, double b) {
    return std::abs(a - 1.0) < std::abs(b - 1.0);
  });
  for (double T : Ts) try_dynamics(T, *first_order);
  const double T_first = scale ? get_parameter(best.p, scale) : 0.0;
  for (double lambda : lambdas) {
    if (lambda == *first_order) continue;
    for (double T : Ts) {
      if (T >= 0.1 * T_first && T <= 10.0 * T_first) try_dynamics(T, lambda);
    }
  }
  // A second, fine pass between the coarse grid's neighbours of the best time constant (steps of
  // 4 %): the delay that goes with a time constant moves with it, so the coarse grid's spacing
  // alone would leave L several samples off for a slow pool.
  // Counted (at most 18 steps span the factor 1.4² at 4 %), and only about a positive time
  // constant: a response no candidate fitted (levels that underflow) leaves the centre at 0.
  const double centre = scale ? get_parameter(best.p, scale) : 0.0;
  if (scale && !Tspec.fixed && !Tspec.initial && centre > 0.0) {
    const double lambda = best.p.lambda, upper = std::min(Tspec.upper, centre * 1.4);
    double T = std::max(Tspec.lower, centre / 1.4);
    for (int step = 0; step < 18 && T <= upper; ++step, T *= 1.04) try_dynamics(T, lambda);
  }
  best.actuation = base_.actuation;
  return best;
}

}  // namespace canalsim::reduced::detail
