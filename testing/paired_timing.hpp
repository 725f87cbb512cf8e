// Two ways of doing the same work timed against each other on a shared, noisy machine: each
// benchmark iteration runs one of each, in alternating order, so that a change of the machine's
// load between calls falls on both alike (a series of either alone varies by 7-12 % here, as much
// as the differences measured). Their ratio is the figure to quote. Either wall seconds, or the CPU
// seconds of the child processes the calls ran and waited for (a whole program's cost, start-up
// included, whatever else the machine runs).
#pragma once

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <chrono>

namespace canalsim::testing {

struct PairedSeconds {
  double first = 0.0;   // mean seconds per call of `first`
  double second = 0.0;  // of `second`
};

enum class Seconds { wall, children_cpu };

inline double children_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_CHILDREN, &usage);
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

template <class Call>
double seconds_of(const Call& call, Seconds measure = Seconds::wall) {
  if (measure == Seconds::children_cpu) {
    const double before = children_cpu_seconds();
    call();
    return children_cpu_seconds() - before;
  }
  const auto start = std::chrono::steady_clock::now();
  call();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Runs the benchmark's loop with one call of each per iteration, `first` first in every other one.
template <class First, class Second>
PairedSeconds time_in_alternating_pairs(benchmark::State& state, const First& first, const Second& second,
                                        Seconds measure = Seconds::wall) {
  double first_seconds = 0.0, second_seconds = 0.0;
  bool first_leads = true;
  for (auto _ : state) {
    if (first_leads) {
      first_seconds += seconds_of(first, measure);
      second_seconds += seconds_of(second, measure);
    } else {
      second_seconds += seconds_of(second, measure);
      first_seconds += seconds_of(first, measure);
    }
    first_leads = !first_leads;
  }
  const double calls = static_cast<double>(state.iterations());
  return {first_seconds / calls, second_seconds / calls};
}

}  // namespace canalsim::testing
