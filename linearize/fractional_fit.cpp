#include "linearize/fractional_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <nlopt.hpp>

namespace canalsim::linearize {
namespace {

using Complex = std::complex<double>;

struct BandData {
  std::vector<double> omega;
  std::vector<Complex> g;
};

// Shape H = e^{−iωL} / (T (iω)^λ + 1); the best real K for it, and the cost at that K.
double cost(const BandData& d, double t, double lambda, double delay, double* gain) {
  // Relative error: minimise Σ |K H_k / G_k − 1|², K = Re Σ conj(H_k/G_k) / Σ |H_k/G_k|².
  double num = 0.0, den = 0.0;
  std::vector<Complex> ratio(d.omega.size());
  for (std::size_t k = 0; k < d.omega.size(); ++k) {
    const double w = d.omega[k];
    const Complex s_lambda = std::pow(w, lambda) * std::exp(Complex(0.0, lambda * M_PI / 2.0));
    const Complex h = std::exp(Complex(0.0, -w * delay)) / (t * s_lambda + 1.0);
    ratio[k] = h / d.g[k];
    num += ratio[k].real();
    den += std::norm(ratio[k]);
  }
  const double k_best = den > 0.0 ? num / den : 0.0;
  double sum = 0.0;
  for (const Complex& r : ratio) sum += std::norm(k_best * r - 1.0);
  if (gain) *gain = k_best;
  return sum / static_cast<double>(ratio.size());
}

// Nelder–Mead on (log T, λ, L) from a start; λ fixed when `fixed_order`.
FractionalFit refine(const BandData& d, double log_t, double lambda, double delay, double max_delay, bool fixed_order) {
  const unsigned dims = fixed_order ? 2 : 3;
  nlopt::opt opt(nlopt::LN_NELDERMEAD, dims);
  std::vector<double> x = fixed_order ? std::vector<double>{log_t, delay} : std::vector<double>{log_t, delay, lambda};
  // NLopt is called with lower < upper on every parameter and sees only finite costs (a response
  // G_k = 0 makes a ratio infinite: Nelder–Mead then only compares it, as the largest number).
  std::vector<double> lower = {std::log(1e-4), 0.0}, upper = {std::log(1e5), std::max(max_delay, 1e-9)};
  if (!fixed_order) {
    lower.push_back(0.1);
    upper.push_back(1.5);
  }
  for (unsigned i = 0; i < dims; ++i) x[i] = std::clamp(x[i], lower[i], upper[i]);
  opt.set_lower_bounds(lower);
  opt.set_upper_bounds(upper);
  struct Context {
    const BandData* d;
    bool fixed;
  } context{&d, fixed_order};
  opt.set_min_objective(
      [](const std::vector<double>& p, std::vector<double>&, void* data) {
        const auto* c = static_cast<Context*>(data);
        const double value = cost(*c->d, std::exp(p[0]), c->fixed ? 1.0 : p[2], p[1], nullptr);
        return std::isfinite(value) ? value : std::numeric_limits<double>::max();
      },
      &context);
  opt.set_xtol_rel(1e-8);
  opt.set_maxeval(4000);
  double best = 0.0;
  try {
    opt.optimize(x, best);
  } catch (const std::exception&) {
    // Nelder–Mead's roundoff stop: x holds the best point found.
  }
  FractionalFit f;
  f.time = std::exp(x[0]);
  f.delay = x[1];
  f.order = fixed_order ? 1.0 : x[2];
  f.rms_relative_error = std::sqrt(cost(d, f.time, f.order, f.delay, &f.gain));
  return f;
}

FractionalFit best_fit(const BandData& d, double max_delay, bool fixed_order) {
  // The cost is multimodal in L (whole turns of phase at the band's top): scan L finely (an
  // eighth of a turn at ω_high) with a few (T, λ) for each, then refine the four best starts.
  struct Start {
    double cost, log_t, lambda, delay;
  };
  std::vector<Start> starts;
  const double centre = std::sqrt(d.omega.front() * d.omega.back());
  const double step = std::max(M_PI / (4.0 * d.omega.back()), max_delay / 400.0);
  for (double delay = 0.0; delay <= max_delay + 1e-12; delay += step) {
    Start best{INFINITY, 0.0, 1.0, delay};
    for (double lambda : fixed_order ? std::vector<double>{1.0} : std::vector<double>{0.4, 0.7, 1.0, 1.3}) {
      for (double t_scale : {0.1, 0.3, 1.0, 3.0, 10.0}) {
        const double log_t = std::log(t_scale / std::pow(centre, lambda));
        const double c = cost(d, std::exp(log_t), lambda, delay, nullptr);
        if (c < best.cost) best = {c, log_t, lambda, delay};
      }
    }
    starts.push_back(best);
  }
  std::sort(starts.begin(), starts.end(), [](const Start& a, const Start& b) { return a.cost < b.cost; });
  FractionalFit best;
  best.rms_relative_error = INFINITY;
  for (std::size_t i = 0; i < std::min<std::size_t>(4, starts.size()); ++i) {
    const FractionalFit f = refine(d, starts[i].log_t, starts[i].lambda, starts[i].delay, max_delay, fixed_order);
    if (f.rms_relative_error < best.rms_relative_error) best = f;
  }
  return best;
}

}  // namespace

Band prbs_band(int stages, double clock_s) {
  const double period = (std::pow(2.0, stages) - 1.0) * clock_s;
  return {2.0 * M_PI / period, 2.0 * M_PI * 0.443 / clock_s};
}

FractionalFit fit_fractional_order(const std::vector<double>& omega, const std::vector<Complex>& response,
                                   const Band& band, double delay_hint) {
  BandData d;
  for (std::size_t k = 0; k < omega.size(); ++k) {
    if (omega[k] >= band.low && omega[k] <= band.high && std::isfinite(std::abs(response[k])) && response[k] != 0.0) {
      d.omega.push_back(omega[k]);
      d.g.push_back(response[k]);
    }
  }
  if (d.omega.size() < 4) throw std::invalid_argument("fit_fractional_order: fewer than 4 frequencies in the band");
  const double max_delay = 2.0 * std::max(delay_hint, 0.0) + 2.0 * M_PI / band.high;
  FractionalFit fit = best_fit(d, max_delay, false);
  fit.integer_rms_relative_error = best_fit(d, max_delay, true).rms_relative_error;
  fit.points = static_cast<int>(d.omega.size());
  return fit;
}

}  // namespace canalsim::linearize
