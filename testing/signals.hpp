// Random test signals shared by the tests (seeded, so every run sees the same numbers).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace canalsim::testing {

// n samples of Gaussian white noise of standard deviation sigma.
inline std::vector<double> white_noise(std::size_t n, std::uint64_t seed, double sigma = 1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  std::vector<double> x(n);
  for (auto& v : x) v = g(rng);
  return x;
}

// x_k = φ x_{k−1} + e_k, e_k standard normal from a generator seeded with `seed`: an AR(1) series,
// whose autocorrelation at lag m is φ^m.
inline std::vector<double> ar1_noise(double phi, std::size_t n, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> x(n);
  double previous = 0.0;
  for (auto& v : x) previous = v = phi * previous + noise(random);
  return x;
}

}  // namespace canalsim::testing
