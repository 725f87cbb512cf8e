#include "solver/rates_jacobian.hpp"

#include <algorithm>
#include <cmath>

namespace canalsim::solver {

RatesPattern rates_jacobian_pattern(int n) {
  RatesPattern p;
  p.unknowns = 2 * n;
  p.column_start.reserve(static_cast<std::size_t>(2 * n + 1));
  p.row.reserve(static_cast<std::size_t>(2 * n * 2 * kRateColours));
  for (int c = 0; c < n; ++c) {
    for (int m = 0; m < 2; ++m) {
      p.column_start.push_back(static_cast<std::int64_t>(p.row.size()));
      for (int r = std::max(0, c - kRateStencil); r <= std::min(n - 1, c + kRateStencil); ++r) {
        p.row.push_back(2 * r);
        p.row.push_back(2 * r + 1);
      }
    }
  }
  p.column_start.push_back(static_cast<std::int64_t>(p.row.size()));
  return p;
}

bool load_state(Canal& canal, const double* u) {
  std::size_t c = 0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i, ++c) {
      if (!(u[2 * c] >= 0.0) || !std::isfinite(u[2 * c + 1])) return false;
      reach.area()[static_cast<std::size_t>(i)] = u[2 * c];
      reach.discharge()[static_cast<std::size_t>(i)] = u[2 * c + 1];
    }
  }
  return true;
}

void store_state(const Canal& canal, double* u) {
  std::size_t c = 0;
  for (int r = 0; r < canal.reach_count(); ++r) {
    const Reach& reach = canal.reach(r);
    for (int i = 0; i < reach.cells(); ++i, ++c) {
      u[2 * c] = reach.area()[static_cast<std::size_t>(i)];
      u[2 * c + 1] = reach.discharge()[static_cast<std::size_t>(i)];
    }
  }
}

bool rates_jacobian(Canal& canal, double time, double* u, const double* f0, const std::vector<double>& scale,
                    const RatesPattern& pattern, const RatesJacobianOptions& options, double* values,
                    int* evaluations) {
  const int n = pattern.unknowns / 2;
  std::vector<double> step(static_cast<std::size_t>(pattern.unknowns)), rates;
  bool ok = true;
  for (int colour = 0; colour < kRateColours && ok; ++colour) {
    for (int m = 0; m < 2 && ok; ++m) {
      for (int c = colour; c < n; c += kRateColours) {
        const std::size_t j = 2 * static_cast<std::size_t>(c) + static_cast<std::size_t>(m);
        step[j] = options.relative_step * std::max(std::abs(u[j]), scale[j]);
        u[j] += step[j];
      }
      ok = load_state(canal, u);
      if (ok) {
        canal.evaluate_rates(time, rates, options.kinks);
        ++*evaluations;
        ok = std::all_of(rates.begin(), rates.end(), [](double v) { return std::isfinite(v); });
      }
      for (int c = colour; c < n; c += kRateColours) {
        const std::size_t j = 2 * static_cast<std::size_t>(c) + static_cast<std::size_t>(m);
        u[j] -= step[j];
        for (auto k = pattern.column_start[j]; k < pattern.column_start[j + 1]; ++k) {
          const auto row = static_cast<std::size_t>(pattern.row[static_cast<std::size_t>(k)]);
          values[k] = ok ? (rates[row] - f0[row]) / step[j] : 0.0;
        }
      }
    }
  }
  return load_state(canal, u) && ok;
}

}  // namespace canalsim::solver
