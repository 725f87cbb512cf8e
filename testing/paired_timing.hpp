// Two ways of doing the same work timed against each other on a shared, noisy machine: each
// benchmark iteration runs one of each, in alternating order, so that a change of the machine's
// load between calls falls on both alike (a series of either alone varies by 7-12 % here, as much
// as the differences measured). Their ratio is the figure to quote.
#pragma once

#include <benchmark/benchmark.h>

#include <chrono>

namespace canalsim::testing {

struct PairedSeconds {
  double first = 0.0;   // mean seconds per call of `first`
  double second = 0.0;  // of `second`
};

template <class Call>
double seconds_of(const Call& call) {
  const auto start = std::chrono::steady_clock::now();
  call();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Runs the benchmark's loop with one call of each per iteration, `first` first in every other one.
template <class First, class Second>
PairedSeconds time_in_alternating_pairs(benchmark::State& state, const First& first, const Second& second) {
  double first_seconds = 0.0, second_seconds = 0.0;
  bool first_leads = true;
  for (auto _ : state) {
    if (first_leads) {
      first_seconds += seconds_of(first);
      second_seconds += seconds_of(second);
    } else {
      second_seconds += seconds_of(second);
      first_seconds += seconds_of(first);
    }
    first_leads = !first_leads;
  }
  const double calls = static_cast<double>(state.iterations());
  return {first_seconds / calls, second_seconds / calls};
}

}  // namespace canalsim::testing
