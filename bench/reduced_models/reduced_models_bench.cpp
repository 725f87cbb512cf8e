// Speed of the reduced-model module: one LFOM fit with the delay search on 20,000 samples
// (target ≤ 0.1 s), one LIOM fit of a slow pool's step test on 10⁶ samples (target ≤ 1 s), and
// the cost of GL simulation with short memory (N = 500), full memory by
// FFT divide and conquer, and full memory by direct summation, against n.
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/recording.hpp"
#include "reduced_models/identification.hpp"
#include "testing/paired_timing.hpp"
#include "testing/recordings.hpp"
#include "testing/synthetic.hpp"

namespace {

using namespace canalsim::reduced;
namespace testing = canalsim::testing;

// A model of `kind` with the parameter `values`, at the reference head `head_ref_mm` of the
// nonlinear models when one is given.
Model truth_of(ModelKind kind, std::initializer_list<std::pair<const char*, double>> values, double head_ref_mm = 0.0) {
  Model truth{kind, {}, {}};
  testing::set_parameters(truth, values);
  if (head_ref_mm > 0.0) truth.p.head_ref_mm = head_ref_mm;
  return truth;
}

// The response of `truth` to n samples of the synthetic PRBS experiment (testing/synthetic.hpp),
// prepared for the fits.
ExperimentData synthetic_data(const Model& truth, std::size_t n) {
  testing::SyntheticSpec spec;
  spec.n = n;
  return prepare_data(testing::synthetic_recording(truth, spec));
}

Model lfom_truth() { return truth_of(ModelKind::lfom, {{"K", 1.1}, {"T", 2.06}, {"lambda", 0.54}, {"L", 4.9}}); }

ExperimentData lfom_data(std::size_t n) { return synthetic_data(lfom_truth(), n); }

// `criterion`: the library's default, the paper's IAE (the study's tables); or least squares, the
// CLI's default: the IAE search, then the least-squares polish on the whole record, on the
// quantised sensor's mean reading.
void lfom_fit(benchmark::State& state, Criterion criterion) {
  const auto data = lfom_data(static_cast<std::size_t>(state.range(0)));
  FitOptions options;
  options.threads = 1;
  options.criterion = criterion;
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
void BM_LfomFitWithDelaySearch(benchmark::State& state) { lfom_fit(state, Criterion::iae); }
BENCHMARK(BM_LfomFitWithDelaySearch)->Arg(2044)->Arg(20000)->Unit(benchmark::kMillisecond)
    ->UseRealTime();
void BM_LfomLeastSquaresFit(benchmark::State& state) { lfom_fit(state, Criterion::least_squares); }
BENCHMARK(BM_LfomLeastSquaresFit)->Arg(20000)->Unit(benchmark::kMillisecond);

// `canalsim fit -m lfom FILE` — the default fit, the least-squares polish included, as a whole
// process: reading the CSV, the fit, its statistics, the table — against the same fit written with
// SciPy (scipy_lfom_fit.py: lfilter for the Grünwald–Letnikov recursion, least_squares over a grid
// of whole-sample delays, then L free) on the same file. CPU seconds of each process, in
// alternating pairs; the ratio is the figure (target: canalsim ≤ 0.15 s and ≥ 100× faster).
void BM_FitCommandAgainstScipy(benchmark::State& state) {
  testing::SyntheticSpec spec;
  spec.n = static_cast<std::size_t>(state.range(0));
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("canalsim_bench_lfom_" + std::to_string(::getpid()) + ".csv");
  canalsim::write_recording(file, testing::synthetic_recording(lfom_truth(), spec));
  const std::string canalsim_fit = std::string(CANALSIM_PROGRAM) + " fit -m lfom " + file.string() + " > /dev/null 2>&1";
  const std::string scipy_fit = std::string("/usr/bin/python3 ") + CANALSIM_SCIPY_FIT + " " + file.string() + " > /dev/null 2>&1";
  const auto run = [](const std::string& command) {
    if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  };
  const testing::PairedSeconds cpu = testing::time_in_alternating_pairs(
      state, [&] { run(canalsim_fit); }, [&] { run(scipy_fit); }, testing::Seconds::children_cpu);
  std::filesystem::remove(file);
  state.counters["canalsim_cpu_s"] = cpu.first;
  state.counters["scipy_cpu_s"] = cpu.second;
  state.counters["ratio"] = cpu.second / cpu.first;
}
BENCHMARK(BM_FitCommandAgainstScipy)->Arg(20000)->Iterations(2)->Unit(benchmark::kSecond)->UseRealTime();

// A slow pool (T = 1 h, L = 5 min) under a gate step every 4 h, 10⁶ samples of 0.125 s (35 h), in
// closed form: y = y0 + Σ_j K ΔA_j (1 − e^{−(t − t_j − L)/T}), noise 0.03 mm, 0.1 mm resolution.
ExperimentData slow_pool_step_test(std::size_t n) {
  const double h = 0.125, K = 1.7, T = 3600.0, L = 300.0, every = 4.0 * 3600.0;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<double> t(n), u(n), y(n);
  for (std::size_t k = 0; k < n; ++k) {
    t[k] = h * static_cast<double>(k);
    const auto step = static_cast<long>(t[k] / every);
    u[k] = 20.0 + ((step % 2 == 1) ? 5.0 : 0.0);
    double level = 45.0;
    for (long j = 1; j <= step + 1; ++j) {
      const double since = t[k] - static_cast<double>(j) * every - L;
      if (since > 0.0) level += K * (j % 2 == 1 ? 5.0 : -5.0) * (1.0 - std::exp(-since / T));
    }
    y[k] = 0.1 * std::round((level + noise(rng)) / 0.1);
  }
  return prepare_data(testing::command_and_level("slow_pool.csv", std::move(t), std::move(u), std::move(y)));
}

void BM_LiomFitSlowPoolStepTest(benchmark::State& state) {
  const auto data = slow_pool_step_test(static_cast<std::size_t>(state.range(0)));
  FitOptions options;
  options.threads = 1;
  Model fitted;
  double nrmse = 0.0;
  int evaluations = 0;
  for (auto _ : state) {
    const auto r = fit(ModelKind::liom, data, options);
    fitted = r.model;
    nrmse = r.nrmse.front();
    evaluations = r.evaluations;
    benchmark::DoNotOptimize(r.model.p.K);
  }
  state.counters["K"] = fitted.p.K;
  state.counters["T_s"] = fitted.p.T;
  state.counters["L_s"] = fitted.p.L;
  state.counters["nrmse"] = nrmse;
  state.counters["evaluations"] = evaluations;
}
BENCHMARK(BM_LiomFitSlowPoolStepTest)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_NlfomSFit(benchmark::State& state) {
  const Model truth =
      truth_of(ModelKind::nlfom_s, {{"K", 1.56}, {"T", 2.3}, {"lambda", 0.66}, {"gamma", 0.6}, {"L", 4.9}}, 15.0);
  const auto data = synthetic_data(truth, static_cast<std::size_t>(state.range(0)));
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
  const Model truth =
      truth_of(ModelKind::nlfom_f, {{"K", 0.78}, {"T", 0.77}, {"lambda", 0.57}, {"gamma", 3.25}, {"L", 4.9}}, 60.0);
  const std::vector<ExperimentData> data{synthetic_data(truth, testing::SyntheticSpec{}.n)};
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
