// The laboratory canal's PRBS experiment end to end: 255.5 s of flow at 100 cells, gate coupling,
// reservoir PID and sensors included, from the settled operating point. Reports the simulated
// seconds per wall-clock second ("x real time") as items_per_second.
#include <benchmark/benchmark.h>

#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"
#include "solver/boundary.hpp"
#include "solver/steady_state.hpp"

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

// The initial steady state of the lab canal (op2, fixed 60 mm supply) from the flat first guess:
// Newton (KINSOL + KLU) against time marching until the depths are within 1e-8 m of it (55 s of
// flow in this small, well-damped flume; measured, see bench/README.md).
canalsim::scenarios::BuiltCanal lab_op2_canal() {
  auto lab = builtin_scenario("lab");
  lab.upstream.kind = canalsim::scenarios::UpstreamKind::level;
  canalsim::scenarios::ExperimentSpec e = *lab.find_experiment("op2");
  e.input.kind = canalsim::scenarios::InputKind::constant;
  return canalsim::scenarios::build_canal(lab, e);
}

void BM_SteadyStateNewton(benchmark::State& state) {
  for (auto _ : state) {
    auto built = lab_op2_canal();
    const auto summary = canalsim::solver::solve_steady_state(built.canal);
    if (!summary.status) state.SkipWithError(summary.status.message().c_str());
    state.counters["newton_iterations"] = summary.iterations;
  }
}
BENCHMARK(BM_SteadyStateNewton)->Unit(benchmark::kMillisecond);

void BM_SteadyStateTimeMarchingTo1e8(benchmark::State& state) {
  for (auto _ : state) {
    auto built = lab_op2_canal();
    if (!built.canal.advance_to(55.0)) state.SkipWithError("marching failed");
  }
}
BENCHMARK(BM_SteadyStateTimeMarchingTo1e8)->Unit(benchmark::kMillisecond);

// A slower canal: Goutal & Maurel's 25 m channel over a bump (q = 4.42 m²/s, h_out = 2 m, Manning
// n = 0.03, 100 cells): marching needs 1500 s to come within 1e-8 m (steady_state_test).
canalsim::solver::Canal bump_canal() {
  using namespace canalsim::solver;
  Canal canal;
  ReachSpec spec;
  spec.length = 25.0;
  spec.cells = 100;
  spec.section = {1.0, 0.0};
  spec.manning_n = 0.03;
  for (int i = 0; i < spec.cells; ++i) {
    const double x = (i + 0.5) * 0.25;
    spec.bed_elevation.push_back(x > 8.0 && x < 12.0 ? 0.2 - 0.05 * (x - 10.0) * (x - 10.0) : 0.0);
  }
  spec.initial_depth.assign(100, 2.0);
  (void)canal.add_reach(spec);
  (void)canal.set_boundary(0, End::upstream, FixedDischargeBoundary::constant(4.42));
  (void)canal.set_boundary(0, End::downstream, FixedLevelBoundary::depth(2.0));
  return canal;
}

void BM_BumpSteadyStateNewton(benchmark::State& state) {
  for (auto _ : state) {
    auto canal = bump_canal();
    if (!canalsim::solver::solve_steady_state(canal).status) state.SkipWithError("Newton failed");
  }
}
BENCHMARK(BM_BumpSteadyStateNewton)->Unit(benchmark::kMillisecond);

void BM_BumpSteadyStateTimeMarching1500s(benchmark::State& state) {
  for (auto _ : state) {
    auto canal = bump_canal();
    if (!canal.advance_to(1500.0)) state.SkipWithError("marching failed");
  }
}
BENCHMARK(BM_BumpSteadyStateTimeMarching1500s)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
