// What a case costs rank 0 beyond its work, for the projection to many processes
// (bench/README.md): cases that do nothing but return `bytes` bytes, handed out, computed and sent
// back. Run under mpirun (`mpirun -n 2 bench/cluster/distribute_bench`) it times the round trip
// of a case between two processes; alone, the same loop on one process's threads. Every process
// runs the same fixed number of iterations: each is one collective distribute().
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>

#include "cluster/distribute.hpp"

namespace {

constexpr std::size_t kCases = 2000;

void BM_EmptyCases(benchmark::State& state) {
  const std::string result(static_cast<std::size_t>(state.range(0)), 'r');
  canalsim::cluster::DistributeOptions options;
  options.threads = 1;
  std::size_t received = 0;
  options.on_result = [&](std::size_t, const std::string&) { ++received; };
  for (auto _ : state) {
    benchmark::DoNotOptimize(canalsim::cluster::distribute(kCases, [&](std::size_t) { return result; }, options));
  }
  state.counters["processes"] = canalsim::cluster::processes();
  state.counters["us_per_case"] = benchmark::Counter(static_cast<double>(kCases) * static_cast<double>(state.iterations()),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

}  // namespace

BENCHMARK(BM_EmptyCases)->ArgName("bytes")->Arg(200)->Arg(20000)->Iterations(5)->Repetitions(3)->Unit(benchmark::kMillisecond)->UseRealTime();

int main(int argc, char** argv) {
  const canalsim::cluster::Session job;
  if (!canalsim::cluster::is_root()) std::freopen("/dev/null", "w", stdout);  // rank 0 reports
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
