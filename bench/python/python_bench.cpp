// The Python package's per-call overhead: `canalsim.simulate("lab", "op1")` (scenario text parsed,
// the run, the recording handed over as numpy arrays and made a DataFrame) against the library's
// load_scenario_or_builtin + simulate that the command line calls, timed in one process. The
// machine is shared and its load changes within seconds, so the two are timed in pairs: each
// iteration makes one call of each, in alternating order, and the overhead is the ratio of the two
// sums minus one. The compiled module's own call (no DataFrame) splits it into the Python half and
// the compiled half.
#include <benchmark/benchmark.h>
#include <pybind11/embed.h>

#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"
#include "testing/paired_timing.hpp"

namespace py = pybind11;

namespace {

// One interpreter for the program; the package is this build's (CANALSIM_PYTHON_DIR).
py::module_& canalsim_package() {
  static py::scoped_interpreter interpreter;
  static py::module_ package = [] {
    py::module_::import("sys").attr("path").attr("insert")(0, CANALSIM_PYTHON_DIR);
    return py::module_::import("canalsim");
  }();
  return package;
}

void simulate_from_the_library() {
  const auto lab = canalsim::scenarios::load_scenario_or_builtin("lab");
  benchmark::DoNotOptimize(canalsim::scenarios::simulate(lab, *lab.find_experiment("op1")));
}

enum class PythonLayer { package = 0, compiled_module = 1 };

// Argument: the PythonLayer timed against the library. Counters: the two means per call and the
// overhead in %.
void BM_PythonOverLibraryInPairs(benchmark::State& state) {
  py::module_& package = canalsim_package();
  const py::object package_simulate = package.attr("simulate");
  const py::object module_simulate = package.attr("_canalsim").attr("simulate");
  const py::object lab_text = package.attr("_canalsim").attr("scenario_text")("lab");
  const auto layer = static_cast<PythonLayer>(state.range(0));
  const auto simulate_from_python = [&] {
    if (layer == PythonLayer::package) {
      benchmark::DoNotOptimize(package_simulate("lab", "op1").ptr());
    } else {
      benchmark::DoNotOptimize(module_simulate(lab_text, "lab", "op1", false, py::none()).ptr());
    }
  };

  const canalsim::testing::PairedSeconds seconds =
      canalsim::testing::time_in_alternating_pairs(state, simulate_from_the_library, simulate_from_python);
  state.counters["library_ms"] = 1e3 * seconds.first;
  state.counters["python_ms"] = 1e3 * seconds.second;
  state.counters["overhead_pct"] = 100.0 * (seconds.second / seconds.first - 1.0);
}

}  // namespace

BENCHMARK(BM_PythonOverLibraryInPairs)
    ->ArgName("layer")
    ->Arg(static_cast<int>(PythonLayer::package))
    ->Arg(static_cast<int>(PythonLayer::compiled_module))
    ->Iterations(20)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
