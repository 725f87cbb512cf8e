// Speed of the reduced-model module: one LFOM fit with the delay search on 20,000 samples
// (target ≤ 0.1 s), and the cost of GL simulation with short memory (N = 500), full memory by
// FFT divide and conquer, and full memory by direct summation, against n.
#include <benchmark/benchmark.h>

#include <random>

#include "reduced_models/identification.hpp"
#include "testing/synthetic.hpp"

namespace {

using namespace canalsim::reduced;
namespace testing = canalsim::testing;

ExperimentData lfom_data(std::size_t n) {
  Model truth{ModelKind::lfom, {}, {}};
  truth.p.K = 1.1;
  truth.p.T = 2.06;
  truth.p.lambda = 0.54;
  truth.p.L = 4.9;
  testing::SyntheticSpec spec;
  spec.n = n;
  return prepare_data(testing::synthetic_recording(truth, spec));
}

void BM_LfomFitWithDelaySearch(benchmark::State& state) {
  const auto data = lfom_data(static_cast<std::size_t>(state.range(0)));
  FitOptions options;
  options.threads = 1;
  int evaluations = 0, simulations = 0;
  double nrmse = 0.0;
  for (auto _ : state) {
    const auto r = fit(ModelKind::lfom, data, options);
    evaluations = r.evaluations;
    simulations = r.simulations;
    nrmse = r.nrmse.front();
    benchmark::DoNotOptimize(r.model.p.K);
  }
  state.counters["evaluations"] = evaluations;
  state.counters["simulations"] = simulations;
  state.counters["nrmse"] = nrmse;
}
BENCHMARK(BM_LfomFitWithDelaySearch)->Arg(2044)->Arg(20000)->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_NlfomSFit(benchmark::State& state) {
  Model truth{ModelKind::nlfom_s, {}, {}};
  truth.p.K = 1.56;
  truth.p.T = 2.3;
  truth.p.lambda = 0.66;
  truth.p.gamma = 0.6;
  truth.p.L = 4.9;
  truth.p.head_ref_mm = 15.0;
  testing::SyntheticSpec spec;
  spec.n = static_cast<std::size_t>(state.range(0));
  const auto data = prepare_data(testing::synthetic_recording(truth, spec));
  FitOptions options;
  options.head_ref_mm = 15.0;
  int evaluations = 0;
  for (auto _ : state) {
    const auto r = fit(ModelKind::nlfom_s, data, options);
    evaluations = r.evaluations;
    benchmark::DoNotOptimize(r.model.p.K);
  }
  state.counters["evaluations"] = evaluations;
}
BENCHMARK(BM_NlfomSFit)->Arg(2044)->Unit(benchmark::kMillisecond)->UseRealTime();

// A γ sweep over the paper's grid 0:10:0.05 (201 fits) of NLFOM-F on one PRBS period, on two
// threads (the CLI's `--gamma 0:10:0.05`).
void BM_GammaSweepNlfomF(benchmark::State& state) {
  Model truth{ModelKind::nlfom_f, {}, {}};
  truth.p.K = 0.78;
  truth.p.T = 0.77;
  truth.p.lambda = 0.57;
  truth.p.gamma = 3.25;
  truth.p.L = 4.9;
  truth.p.head_ref_mm = 60.0;
  const std::vector<ExperimentData> data{
      prepare_data(testing::synthetic_recording(truth, testing::SyntheticSpec{}))};
  FitOptions options;
  options.head_ref_mm = 60.0;
  options.threads = 2;
  double best = 0.0;
  for (auto _ : state) {
    const auto sweep = gamma_sweep(ModelKind::nlfom_f, data, options, GammaGrid{0.0, 10.0, 0.05});
    best = sweep.gamma[sweep.best];
  }
  state.counters["best_gamma"] = best;
}
BENCHMARK(BM_GammaSweepNlfomF)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

void gl(benchmark::State& state, GlMemory memory) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  std::vector<double> f(n);
  for (double& v : f) v = dist(rng);
  for (auto _ : state) {
    auto x = solve_fractional_lag(f, 1.5, 0.6, 0.13, {memory, 500});
    benchmark::DoNotOptimize(x.data());
  }
  state.SetComplexityN(state.range(0));
}
void BM_GlShortMemory(benchmark::State& s) { gl(s, GlMemory::short_memory); }
void BM_GlFullMemoryFft(benchmark::State& s) { gl(s, GlMemory::full); }
void BM_GlFullMemoryDirect(benchmark::State& s) { gl(s, GlMemory::full_direct); }
BENCHMARK(BM_GlShortMemory)->RangeMultiplier(4)->Range(1000, 64000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlFullMemoryFft)->RangeMultiplier(4)->Range(1000, 256000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlFullMemoryDirect)->RangeMultiplier(4)->Range(1000, 64000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
