// One calibration of the default parameter set (cd_free, cd_submerged, manning_n,
// downstream_opening_mm, downstream_zero_head_mm, offset_y_dw_mm, offset_y_dwe_mm) on four
// 255.5 s laboratory recordings (op1–op4), as the library's CalibrateOptions run it (`canalsim calibrate --replay
// recorded-upstream`; BM_CalibrateAsTheCommandLineDoes runs the command's defaults). The
// recordings come from a truth the model cannot represent exactly: 1.5× the cells, minmod at
// Courant 0.5, the six parameters perturbed, level noise 0.05 mm on the 0.05 mm quantisation.
// Target: at most 30 s on this 2-core machine (on the scenario's grid; with the grid
// refinement of `canalsim calibrate` the refined grids add their own time). Counters: simulations, LM iterations,
// process_cpu_s (the CPU time of every thread of the process: the machine is shared, so the wall
// time depends on the load, the CPU time much less).
#include <benchmark/benchmark.h>

#include <ctime>

#include "calibration/calibrate.hpp"
#include "diagnosis/diagnose.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"

namespace {

using namespace canalsim;

// The truth's op1–op4 (255.5 s each), named as the files a laboratory would pass.
std::vector<Recording> recordings_of(const scenarios::Scenario& truth) {
  std::vector<Recording> out;
  for (const char* name : {"op1", "op2", "op3", "op4"}) {
    Recording r = scenarios::simulate(truth, *truth.find_experiment(name));
    r.source = std::string(name) + ".csv";
    out.push_back(std::move(r));
  }
  return out;
}

// The truth on `cells` cells (minmod at Courant `cfl`), the six parameters perturbed.
std::vector<Recording> truth_recordings(int cells = 150, double cfl = 0.5) {
  scenarios::Scenario truth = scenarios::builtin_scenario("lab");
  truth.pools.front().cells = cells;
  truth.numerics.van_leer_limiter = false;
  truth.numerics.cfl = cfl;
  truth.head_gate->discharge_coefficient = 0.9;
  truth.head_gate->submerged_discharge_coefficient = 1.1;
  truth.pools.front().manning_n *= 1.5;
  truth.downstream.gate.opening_m += 1e-3;
  truth.sensors.offset_y_dw_mm = 2.0;
  truth.sensors.offset_y_dwe_mm = -1.5;
  truth.sensors.noise_std_mm = 0.05;
  return recordings_of(truth);
}

// A calibration takes seconds to minutes on two threads: each argument is timed once, in
// wall-clock seconds.
void once_in_seconds(benchmark::internal::Benchmark* b) { b->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime(); }

// The timed loop: calibrate the lab on `recordings` with `options`; the counters every benchmark
// here reports. Returns the last calibration.
calibration::Calibration time_calibration(benchmark::State& state, const std::vector<Recording>& recordings,
                                          const calibration::CalibrateOptions& options) {
  const auto lab = scenarios::builtin_scenario("lab");
  calibration::Calibration c;
  double cpu_s = 0.0;
  for (auto _ : state) {
    const std::clock_t before = std::clock();  // process CPU time, all threads (Linux)
    c = calibration::calibrate(lab, recordings, {}, options);
    cpu_s += static_cast<double>(std::clock() - before) / CLOCKS_PER_SEC;
    benchmark::DoNotOptimize(c.parameters.data());
  }
  state.counters["process_cpu_s"] = cpu_s / static_cast<double>(state.iterations());
  state.counters["simulations"] = c.simulations;
  state.counters["cost_ratio"] = c.cost_before > 0.0 ? c.cost_after / c.cost_before : 0.0;
  state.counters["cells"] = c.calibrated.pools.front().cells;
  return c;
}

void BM_CalibrateDefaultSetOnFourLabRecordings(benchmark::State& state) {
  calibration::CalibrateOptions options;
  options.threads = 2;
  options.starts = static_cast<int>(state.range(0));
  options.further_starts_only_when_doubtful = state.range(1) == 0;
  options.grid_refinements = static_cast<int>(state.range(2));
  const calibration::Calibration c = time_calibration(state, truth_recordings(), options);
  state.counters["iterations"] = c.iterations;
  state.counters["starts_run"] = c.starts;
  state.SetLabel(c.ok ? c.starts_note : c.message);
}

// Arguments: starts (at most), always run them (1) or only when the first optimum is doubtful (0,
// the default), grid refinements at most (CalibrateOptions::grid_refinements). {2, 0, 0} is the
// library's default; `canalsim calibrate` runs {2, 0, 2}.
BENCHMARK(BM_CalibrateDefaultSetOnFourLabRecordings)
    ->ArgNames({"starts", "always", "refine"})
    ->Args({2, 0, 0})
    ->Args({2, 1, 0})
    ->Args({1, 0, 0})
    ->Args({2, 0, 2})
    ->Apply(once_in_seconds);

// The grid refinement of `canalsim calibrate` (at most two) on recordings of a truth on 800 cells
// (minmod, Courant 0.45): the grid check finds the lab's 100 cells limit the fit and the
// calibration runs again on 200 and 400 cells. Argument: refinements at most (0: the 100-cell
// calibration alone, for the ratio).
void BM_CalibrateWithGridRefinementOnAFineGridTruth(benchmark::State& state) {
  calibration::CalibrateOptions options;
  options.threads = 2;
  options.grid_refinements = static_cast<int>(state.range(0));
  const calibration::Calibration c = time_calibration(state, truth_recordings(800, 0.45), options);
  state.SetLabel(c.ok ? c.grid_note : c.message);
}

BENCHMARK(BM_CalibrateWithGridRefinementOnAFineGridTruth)
    ->ArgNames({"refine"})
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Apply(once_in_seconds);

// Clean recordings (no noise, no offsets) of an 800-cell truth (minmod, Courant 0.45) whose
// physics differs where an independent simulator's would: its own regularisation of Swamee's law
// near zero head (h0 = 4 mm, where the lab's head gate runs at op3/op4), discharge coefficients
// 0.95 (free) and 0.97 (submerged), Manning n 0.014, the downstream gate 0.5 mm wider. The
// nominal model sits ~2.1 mm off at op3/op4, as it does against an independent simulator of the lab.
std::vector<Recording> clean_independent_recordings() {
  scenarios::Scenario truth = scenarios::builtin_scenario("lab");
  truth.pools.front().cells = 800;
  truth.numerics.van_leer_limiter = false;
  truth.numerics.cfl = 0.45;
  truth.head_gate->discharge_coefficient = 0.95;
  truth.head_gate->submerged_discharge_coefficient = 0.97;
  truth.head_gate->zero_head_m = 4e-3;
  truth.pools.front().manning_n = 0.014;
  truth.downstream.gate.opening_m += 0.5e-3;
  return recordings_of(truth);
}

// What `canalsim calibrate --scenario lab op1.csv ... op4.csv -o cal.toml` runs: the diagnosis'
// replay (diagnosis::calibration_replay_for_diagnosis; the upstream model drives the head gate,
// so the default set adds the y_up offset), two starts at most, two grid refinements at most, the
// grid-converged estimates on twice (or four times) the cells written when they fit better.
// Argument `truth`: 0 the perturbed, noisy 800-cell truth above; 1 clean_independent_recordings().
void BM_CalibrateAsTheCommandLineDoes(benchmark::State& state) {
  calibration::CalibrateOptions options;
  options.threads = 2;
  options.grid_refinements = 2;
  options.write_grid_converged = true;
  options.replay = diagnosis::calibration_replay_for_diagnosis();
  const std::vector<Recording> recordings =
      state.range(0) == 0 ? truth_recordings(800, 0.45) : clean_independent_recordings();
  const calibration::Calibration c = time_calibration(state, recordings, options);
  state.counters["starts_run"] = c.starts;
  state.counters["parameters"] = static_cast<double>(c.parameters.size());
  state.SetLabel(c.ok ? c.starts_note : c.message);
}

BENCHMARK(BM_CalibrateAsTheCommandLineDoes)
    ->ArgNames({"truth"})
    ->Arg(0)
    ->Arg(1)
    ->Apply(once_in_seconds);

}  // namespace

BENCHMARK_MAIN();
