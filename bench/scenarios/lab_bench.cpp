// The laboratory canal's PRBS experiment end to end: 255.5 s of flow at 100 cells, gate coupling,
// reservoir PID and sensors included, from the settled operating point. Reports the simulated
// seconds per wall-clock second ("x real time") as items_per_second.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>

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

// The initial steady state of the lab canal (op2, fixed 60 mm supply) from the flat first guess
// the scenario builder uses (the pool at 85% of the supply level, at rest): Newton (KINSOL + KLU)
// against time marching from the same start until every depth is within 1e-8 m of Newton's
// answer (checked after every step; the simulated time it took is reported). Building the canal
// (parsing the scenario) is not timed in either.
canalsim::scenarios::BuiltCanal lab_op2_canal() {
  auto lab = builtin_scenario("lab");
  lab.upstream.kind = canalsim::scenarios::UpstreamKind::level;
  canalsim::scenarios::ExperimentSpec e = *lab.find_experiment("op2");
  e.input.kind = canalsim::scenarios::InputKind::constant;
  return canalsim::scenarios::build_canal(lab, e);
}

// Depths of every cell of every reach, in order.
std::vector<double> depths(const canalsim::solver::Canal& canal) {
  std::vector<double> h;
  for (int r = 0; r < canal.reach_count(); ++r) {
    for (int i = 0; i < canal.reach(r).cells(); ++i) h.push_back(canal.reach(r).depth(i));
  }
  return h;
}

// Steps until every depth is within `tolerance` of `target`; false if the run fails or takes
// longer than t_max.
bool march_until_within(canalsim::solver::Canal& canal, const std::vector<double>& target,
                        double tolerance, double t_max) {
  for (;;) {
    const auto h = depths(canal);
    double worst = 0.0;
    for (std::size_t i = 0; i < h.size(); ++i) worst = std::max(worst, std::abs(h[i] - target[i]));
    if (worst < tolerance) return true;
    if (canal.time() > t_max || !canal.step()) return false;
  }
}

// The canal a builder returns: a scenario's BuiltCanal holds its solver canal.
canalsim::solver::Canal& canal_of(canalsim::scenarios::BuiltCanal& built) { return built.canal; }
canalsim::solver::Canal& canal_of(canalsim::solver::Canal& canal) { return canal; }

// `timed` on a fresh canal from `make` at every iteration; building it is not timed.
template <class Make, class Timed>
void time_on_fresh_canals(benchmark::State& state, Make make, Timed timed) {
  for (auto _ : state) {
    state.PauseTiming();
    auto built = make();
    state.ResumeTiming();
    timed(canal_of(built));
  }
}

// Newton's steady state, with its iterations and residual evaluations.
template <class Make>
void time_newton(benchmark::State& state, Make make) {
  time_on_fresh_canals(state, make, [&state](canalsim::solver::Canal& canal) {
    const auto summary = canalsim::solver::solve_steady_state(canal);
    if (!summary.status) state.SkipWithError(summary.status.message().c_str());
    state.counters["newton_iterations"] = summary.iterations;
    state.counters["residual_evaluations"] = summary.residual_evaluations;
  });
}

// Time marching until every depth is within 1e-8 m of Newton's steady state (at most t_max s),
// with the simulated time it took in `unit_s` (`counter`).
template <class Make>
void time_marching(benchmark::State& state, Make make, double t_max, const char* counter, double unit_s) {
  auto reference = make();
  (void)canalsim::solver::solve_steady_state(canal_of(reference));
  const std::vector<double> target = depths(canal_of(reference));
  time_on_fresh_canals(state, make, [&](canalsim::solver::Canal& canal) {
    if (!march_until_within(canal, target, 1e-8, t_max)) state.SkipWithError("marching failed");
    state.counters[counter] = canal.time() / unit_s;
  });
}

void BM_SteadyStateNewton(benchmark::State& state) { time_newton(state, lab_op2_canal); }
BENCHMARK(BM_SteadyStateNewton)->Unit(benchmark::kMicrosecond);

void BM_SteadyStateTimeMarchingTo1e8(benchmark::State& state) {
  time_marching(state, lab_op2_canal, 1000.0, "simulated_s", 1.0);
}
BENCHMARK(BM_SteadyStateTimeMarchingTo1e8)->Unit(benchmark::kMillisecond);

// A slower canal: Goutal & Maurel's 25 m channel over a bump (q = 4.42 m²/s, h_out = 2 m, Manning
// n = 0.03, 100 cells), from a flat 2 m at rest.
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

void BM_BumpSteadyStateNewton(benchmark::State& state) { time_newton(state, bump_canal); }
BENCHMARK(BM_BumpSteadyStateNewton)->Unit(benchmark::kMicrosecond);

void BM_BumpSteadyStateTimeMarchingTo1e8(benchmark::State& state) {
  time_marching(state, bump_canal, 5000.0, "simulated_s", 1.0);
}
BENCHMARK(BM_BumpSteadyStateTimeMarchingTo1e8)->Unit(benchmark::kMillisecond);

// An irrigation canal: ASCE test canal 2 (Corning; 8 trapezoidal pools, 28 km, 280 cells,
// drowned checks, orifice offtakes, end pump; docs/asce-canals.md) from the builder's start (the
// design backwater profile with its design discharges). Its pools settle with time constants of hours, which is
// where a steady-state solver earns its keep.
canalsim::scenarios::BuiltCanal asce2_canal() {
  const auto asce2 = builtin_scenario("asce2");
  return canalsim::scenarios::build_canal(asce2, *asce2.find_experiment("steady"));
}

void BM_Asce2SteadyStateNewton(benchmark::State& state) { time_newton(state, asce2_canal); }
BENCHMARK(BM_Asce2SteadyStateNewton)->Unit(benchmark::kMillisecond);

void BM_Asce2SteadyStateTimeMarchingTo1e8(benchmark::State& state) {
  time_marching(state, asce2_canal, 60.0 * 86400.0, "simulated_h", 3600.0);
}
BENCHMARK(BM_Asce2SteadyStateTimeMarchingTo1e8)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
