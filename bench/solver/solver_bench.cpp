// Cell updates per second of the solver's full time step (bench/README.md, "Solver").
//
// Each iteration is one Canal::step(): for the second-order scheme two stages of primitives,
// limited slopes, hydrostatically reconstructed HLL fluxes and update, plus the boundaries and the
// CFL reduction; items_per_second = cells × steps / s.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>

#include "solver/canal.hpp"

namespace {

using namespace canalsim::solver;

// A wavy, flowing state that stays smooth for many steps: h = h0 (1 + 0.1 sin), Q = 0.3 A c0.
std::unique_ptr<Canal> make_canal(int cells, double length, Section section, double depth, double manning,
                                  SpatialOrder order) {
  SolverOptions options;
  options.order = order;
  auto canal = std::make_unique<Canal>(options);
  ReachSpec spec;
  spec.length = length;
  spec.cells = cells;
  spec.section = section;
  spec.manning_n = manning;
  const double c0 = std::sqrt(9.81 * depth);
  for (int i = 0; i < cells; ++i) {
    const double x = (i + 0.5) / cells;
    const double h = depth * (1.0 + 0.1 * std::sin(2.0 * M_PI * 4.0 * x));
    spec.initial_depth.push_back(h);
    spec.initial_discharge.push_back(0.3 * section.area(h) * c0);
  }
  if (!canal->add_reach(spec)) std::abort();
  canal->set_boundary(0, End::upstream, std::make_shared<WallBoundary>());
  canal->set_boundary(0, End::downstream, std::make_shared<WallBoundary>());
  return canal;
}

void run_steps(benchmark::State& state, Canal& canal, int cells) {
  for (auto _ : state) {
    if (!canal.step()) state.SkipWithError("step failed");
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * cells);
}

// Steps of a 1000 m reach, 1 m deep, of the benchmark's argument in cells.
void run_steps_of_a_km(benchmark::State& state, Section section, double manning, SpatialOrder order) {
  const int cells = static_cast<int>(state.range(0));
  auto canal = make_canal(cells, 1000.0, section, 1.0, manning, order);
  run_steps(state, *canal, cells);
}

// Full second-order step, rectangular 1 m wide channel, 1 m deep, frictionless.
void BM_SecondOrderStep(benchmark::State& state) {
  run_steps_of_a_km(state, {1.0, 0.0}, 0.0, SpatialOrder::second);
}
BENCHMARK(BM_SecondOrderStep)->RangeMultiplier(10)->Range(100, 100000);

// Same with Manning friction (n = 0.015).
void BM_SecondOrderStepFriction(benchmark::State& state) {
  run_steps_of_a_km(state, {1.0, 0.0}, 0.015, SpatialOrder::second);
}
BENCHMARK(BM_SecondOrderStepFriction)->RangeMultiplier(10)->Range(100, 100000);

// General trapezoidal path (b = 2 m, m = 1.5), friction.
void BM_SecondOrderStepTrapezoidal(benchmark::State& state) {
  run_steps_of_a_km(state, {2.0, 1.5}, 0.015, SpatialOrder::second);
}
BENCHMARK(BM_SecondOrderStepTrapezoidal)->RangeMultiplier(10)->Range(100, 100000);

// The laboratory canal: 5 m, 100 cells, 0.08 m wide rectangle, 60 mm deep, n = 0.010.
void BM_LabCanalSecondOrderStep(benchmark::State& state) {
  auto canal = make_canal(100, 5.0, {0.08, 0.0}, 0.06, 0.010, SpatialOrder::second);
  run_steps(state, *canal, 100);
}
BENCHMARK(BM_LabCanalSecondOrderStep);

// First-order HLL (piecewise constant, forward Euler) for comparison.
void BM_FirstOrderStep(benchmark::State& state) {
  run_steps_of_a_km(state, {1.0, 0.0}, 0.0, SpatialOrder::first);
}
BENCHMARK(BM_FirstOrderStep)->RangeMultiplier(10)->Range(100, 100000);

}  // namespace

BENCHMARK_MAIN();
