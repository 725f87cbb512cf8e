#include "reduced_models/gl.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define CANALSIM_HAVE_AVX2_PATH 1
#endif

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

// The short-memory GL sum (a 500-term dot product per sample) is the hot loop of every fit. The
// project builds without -march for portability, which leaves Eigen on SSE2; on processors with
// AVX2 and FMA a hand-vectorised kernel, chosen at run time, does four multiply-adds per
// instruction in four independent accumulators.
using DotKernel = double (*)(const double*, const double*, std::size_t);

double dot_portable(const double* a, const double* b, std::size_t n) {
  const Eigen::Map<const Eigen::VectorXd> va(a, static_cast<Eigen::Index>(n));
  const Eigen::Map<const Eigen::VectorXd> vb(b, static_cast<Eigen::Index>(n));
  return va.dot(vb);
}

#ifdef CANALSIM_HAVE_AVX2_PATH
__attribute__((target("avx2,fma"))) double dot_avx2(const double* a, const double* b,
                                                    std::size_t n) {
  __m256d acc0 = _mm256_setzero_pd(), acc1 = _mm256_setzero_pd();
  __m256d acc2 = _mm256_setzero_pd(), acc3 = _mm256_setzero_pd();
  std::size_t i = 0;
  for (; i + 16 <= n; i += 16) {
    acc0 = _mm256_fmadd_pd(_mm256_loadu_pd(a + i), _mm256_loadu_pd(b + i), acc0);
    acc1 = _mm256_fmadd_pd(_mm256_loadu_pd(a + i + 4), _mm256_loadu_pd(b + i + 4), acc1);
    acc2 = _mm256_fmadd_pd(_mm256_loadu_pd(a + i + 8), _mm256_loadu_pd(b + i + 8), acc2);
    acc3 = _mm256_fmadd_pd(_mm256_loadu_pd(a + i + 12), _mm256_loadu_pd(b + i + 12), acc3);
  }
  for (; i + 4 <= n; i += 4) {
    acc0 = _mm256_fmadd_pd(_mm256_loadu_pd(a + i), _mm256_loadu_pd(b + i), acc0);
  }
  const __m256d sum4 = _mm256_add_pd(_mm256_add_pd(acc0, acc1), _mm256_add_pd(acc2, acc3));
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, sum4);
  double sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
  for (; i < n; ++i) sum += a[i] * b[i];
  return sum;
}
#endif

DotKernel select_dot_kernel() {
#ifdef CANALSIM_HAVE_AVX2_PATH
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return dot_avx2;
#endif
  return dot_portable;
}

double lagged_dot(const double* a, const double* b, std::size_t n) {
  static const DotKernel kernel = select_dot_kernel();
  return kernel(a, b, n);
}

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

Status GlOptions::validate() const {
  return Validator()
      .require(memory != GlMemory::short_memory || memory_terms >= 1, "memory_terms",
               static_cast<double>(memory_terms), "at least 1 for short memory (paper: 500)")
      .status();
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
  if (const Status status = options.validate(); !status) throw std::invalid_argument("GL options: " + status.message());
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
      // Weights past the series' length are never reached (m = min(k, N) < n): capping N there
      // changes nothing and keeps --memory-terms 1e8 from allocating 1.6 GB per simulation.
      const std::size_t N = std::min(terms, n);
      const auto w = gl_weights(lambda, N + 1);
      // Reversed weights: wr[i] = w_{N−i}, so s_k = Σ_i wr[N−m+i] x_{k−m+i} is a contiguous dot
      // product.
      std::vector<double> wr(N);
      for (std::size_t i = 0; i < N; ++i) wr[i] = w[N - i];
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t m = std::min(k, N);
        const double s = m > 0 ? lagged_dot(wr.data() + (N - m), x + (k - m), m) : 0.0;
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
