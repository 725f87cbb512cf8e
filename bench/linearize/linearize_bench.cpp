// The frequency response of the linearised canal: 200 log-spaced frequencies (the command's
// default grid) on the laboratory canal (100 cells, reservoir: 202 states) and on ASCE canal 2
// (8 pools, 280 cells: 560 states). "sweep" is the 200 complex sparse LUs alone; "linearize" is
// the whole `canalsim linearize` computation: building the canal, the Newton steady state, the
// Jacobians, the sweep, the static gain, the dense eigen-solve for the poles and the delay.
#include <benchmark/benchmark.h>

#include "linearize/linearize.hpp"
#include "scenarios/builtin.hpp"

namespace {

using namespace canalsim;

struct Case {
  const char* scenario;
  const char* experiment;
  linearize::InputChoice input;
  linearize::OutputChoice output;
};

const Case kLab{"lab", "op2", {linearize::InputKind::gate, 0}, {linearize::OutputKind::y_dwe, 0}};
const Case kAsce2{"asce2", "steady", {linearize::InputKind::inflow, 0}, {linearize::OutputKind::y_check, 8}};

void sweep(benchmark::State& state, const Case& c) {
  const scenarios::Scenario s = scenarios::builtin_scenario(c.scenario);
  const linearize::StateSpace sys = linearize::linearize_system(s, *s.find_experiment(c.experiment), c.input, c.output);
  const std::vector<double> omega = linearize::log_grid({1e-4 * sys.nyquist, 0.5 * sys.nyquist, 200});
  for (auto _ : state) benchmark::DoNotOptimize(linearize::frequency_response(sys, omega));
  state.counters["states"] = static_cast<double>(sys.A.rows());
}

void whole(benchmark::State& state, const Case& c) {
  const scenarios::Scenario s = scenarios::builtin_scenario(c.scenario);
  linearize::LinearizeOptions options;
  options.input = c.input;
  options.output = c.output;
  for (auto _ : state) benchmark::DoNotOptimize(linearize::linearize(s, *s.find_experiment(c.experiment), options));
}

BENCHMARK_CAPTURE(sweep, lab_200_frequencies, kLab)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(whole, lab_linearize, kLab)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(sweep, asce2_200_frequencies, kAsce2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(whole, asce2_linearize, kAsce2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
