#include "reduced_models/gl.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

namespace canalsim::reduced {
namespace {

// Linear convolution by FFT with reusable buffers (sizes are powers of two, so kissfft plans
// are reused across calls).
class FftConvolver {
 public:
  // out[i] = (a * b)[i] for i < na + nb − 1.
  const std::vector<double>& convolve(const double* a, std::size_t na, const double* b,
                                      std::size_t nb) {
    std::size_t size = 1;
    while (size < na + nb - 1) size <<= 1;
    ta_.assign(size, 0.0);
    tb_.assign(size, 0.0);
    std::copy(a, a + na, ta_.begin());
    std::copy(b, b + nb, tb_.begin());
    fft_.fwd(fa_, ta_);
    fft_.fwd(fb_, tb_);
    for (std::size_t i = 0; i < fa_.size(); ++i) fa_[i] *= fb_[i];
    fft_.inv(out_, fa_);
    out_.resize(na + nb - 1);
    return out_;
  }

 private:
  Eigen::FFT<double> fft_;
  std::vector<double> ta_, tb_, out_;
  std::vector<std::complex<double>> fa_, fb_;
};

constexpr std::size_t kLeaf = 64;        // blocks solved with direct sums
constexpr std::size_t kFftBlock = 512;   // cross-block contributions by FFT from this size up

struct FullMemorySolver {
  const std::vector<double>& w;
  double c;
  const OnlineForcing& forcing;
  double* x;
  std::vector<double> s;
  FftConvolver conv;

  void step(std::size_t k) { x[k] = (forcing(k, x) - c * s[k]) / (1.0 + c); }

  void solve(std::size_t l, std::size_t r) {
    if (r - l <= kLeaf) {
      for (std::size_t k = l; k < r; ++k) {
        double acc = 0.0;
        for (std::size_t i = l; i < k; ++i) acc += w[k - i] * x[i];
        s[k] += acc;
        step(k);
      }
      return;
    }
    const std::size_t m = l + (r - l) / 2;
    solve(l, m);
    // s_k += Σ_{i=l}^{m−1} w_{k−i} x_i for k in [m, r); k − i runs over 1 … r−l−1.
    if (r - l < kFftBlock) {
      for (std::size_t k = m; k < r; ++k) {
        double acc = 0.0;
        for (std::size_t i = l; i < m; ++i) acc += w[k - i] * x[i];
        s[k] += acc;
      }
    } else {
      const auto& y = conv.convolve(x + l, m - l, w.data() + 1, r - l - 1);
      for (std::size_t k = m; k < r; ++k) s[k] += y[k - l - 1];
    }
    solve(m, r);
  }
};

void check_arguments(double T, double lambda, double h) {
  if (!(T >= 0.0) || !std::isfinite(T)) {
    throw std::invalid_argument("solve_fractional_lag: T = " + std::to_string(T) +
                                ", expected a finite T >= 0");
  }
  if (!(lambda > 0.0) || !std::isfinite(lambda)) {
    throw std::invalid_argument("solve_fractional_lag: lambda = " + std::to_string(lambda) +
                                ", expected a finite lambda > 0");
  }
  if (!(h > 0.0) || !std::isfinite(h)) {
    throw std::invalid_argument("solve_fractional_lag: h = " + std::to_string(h) +
                                ", expected a finite h > 0");
  }
}

}  // namespace

std::string GlOptions::validate() const {
  if (memory == GlMemory::short_memory && memory_terms < 1) {
    return "GlOptions.memory_terms: must be at least 1 for short memory (paper: 500)";
  }
  return "";
}

std::vector<double> gl_weights(double lambda, std::size_t count) {
  std::vector<double> w(count);
  if (count == 0) return w;
  w[0] = 1.0;
  for (std::size_t j = 1; j < count; ++j) {
    w[j] = w[j - 1] * (1.0 - (lambda + 1.0) / static_cast<double>(j));
  }
  return w;
}

void solve_fractional_lag(std::size_t n, double T, double lambda, double h,
                          const GlOptions& options, const OnlineForcing& forcing, double* x) {
  check_arguments(T, lambda, h);
  if (const auto why = options.validate(); !why.empty()) throw std::invalid_argument(why);
  if (n == 0) return;
  const double c = T * std::pow(h, -lambda);
  if (c == 0.0) {
    for (std::size_t k = 0; k < n; ++k) x[k] = forcing(k, x);
    return;
  }
  // λ = 1: w = (1, −1, 0, …), so every memory choice is exactly backward Euler.
  GlMemory memory = options.memory;
  std::size_t terms = options.memory_terms;
  if (lambda == 1.0) {
    memory = GlMemory::short_memory;
    terms = 1;
  }
  const double inv = 1.0 / (1.0 + c);
  switch (memory) {
    case GlMemory::short_memory: {
      const std::size_t N = terms;
      const auto w = gl_weights(lambda, N + 1);
      // Reversed weights: wr[i] = w_{N−i}, so s_k = Σ_i wr[N−m+i] x_{k−m+i} is a contiguous dot
      // product (the hot loop of every fit; Eigen's dot uses vector lanes and several
      // accumulators).
      Eigen::VectorXd wr(static_cast<Eigen::Index>(N));
      for (std::size_t i = 0; i < N; ++i) wr[static_cast<Eigen::Index>(i)] = w[N - i];
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t m = std::min(k, N);
        double s = 0.0;
        if (m > 0) {
          const Eigen::Map<const Eigen::VectorXd> past(x + (k - m), static_cast<Eigen::Index>(m));
          s = wr.tail(static_cast<Eigen::Index>(m)).dot(past);
        }
        x[k] = (forcing(k, x) - c * s) * inv;
      }
      return;
    }
    case GlMemory::full_direct: {
      const auto w = gl_weights(lambda, n);
      for (std::size_t k = 0; k < n; ++k) {
        double s = 0.0;
        for (std::size_t j = 1; j <= k; ++j) s += w[j] * x[k - j];
        x[k] = (forcing(k, x) - c * s) * inv;
      }
      return;
    }
    case GlMemory::full: {
      const auto w = gl_weights(lambda, n);
      FullMemorySolver solver{w, c, forcing, x, std::vector<double>(n, 0.0), {}};
      solver.solve(0, n);
      return;
    }
  }
}

std::vector<double> solve_fractional_lag(const std::vector<double>& f, double T, double lambda,
                                         double h, const GlOptions& options) {
  std::vector<double> x(f.size());
  const OnlineForcing forcing = [&f](std::size_t k, const double*) { return f[k]; };
  solve_fractional_lag(f.size(), T, lambda, h, options, forcing, x.data());
  return x;
}

double short_memory_steady_state(double T, double lambda, double h, std::size_t memory_terms) {
  const auto w = gl_weights(lambda, memory_terms + 1);
  double sum = 0.0;
  for (double v : w) sum += v;
  return 1.0 / (1.0 + T * std::pow(h, -lambda) * sum);
}

}  // namespace canalsim::reduced
