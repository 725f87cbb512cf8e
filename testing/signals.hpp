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

}  // namespace canalsim::testing
