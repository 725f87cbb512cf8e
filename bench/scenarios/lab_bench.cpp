// The laboratory canal's PRBS experiment end to end: 255.5 s of flow at 100 cells, gate coupling,
// reservoir PID and sensors included, from the settled operating point. Reports the simulated
// seconds per wall-clock second ("x real time") as items_per_second.
#include <benchmark/benchmark.h>

#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"

namespace {

using canalsim::scenarios::builtin_scenario;
using canalsim::scenarios::simulate;
using canalsim::scenarios::SimulateOptions;

void BM_LabPrbsExperiment(benchmark::State& state, const char* experiment) {
  const auto lab = builtin_scenario("lab");
  const auto& e = *lab.find_experiment(experiment);
  SimulateOptions options;
  options.settle_time = 0.0;  // the run alone; settling is the steady-state solver's job
  for (auto _ : state) {
    const auto recording = simulate(lab, e, options);
    benchmark::DoNotOptimize(recording.columns.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * e.duration_s));
  state.counters["x_real_time"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * e.duration_s, benchmark::Counter::kIsRate);
}

BENCHMARK_CAPTURE(BM_LabPrbsExperiment, op2_submerged, "op2")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_LabPrbsExperiment, op4_free, "op4")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
