// The Python package's per-call overhead: `canalsim.simulate("lab", "op1")` (scenario text parsed,
// the run, the recording handed over as numpy arrays and made a DataFrame) against the library's
// load_scenario_or_builtin + simulate that the command line calls, timed in one process so that
// the machine's load falls on both alike. The overhead is the ratio of the two medians minus one;
// the module's own call (no DataFrame) splits it into the Python half and the compiled half.
#include <benchmark/benchmark.h>
#include <pybind11/embed.h>

#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"

namespace py = pybind11;

namespace {

void BM_SimulateFromTheLibrary(benchmark::State& state) {
  for (auto _ : state) {
    const auto lab = canalsim::scenarios::load_scenario_or_builtin("lab");
    benchmark::DoNotOptimize(canalsim::scenarios::simulate(lab, *lab.find_experiment("op1")));
  }
}

// One interpreter for the program; the package is this build's (CANALSIM_PYTHON_DIR).
py::module_& canalsim_package() {
  static py::scoped_interpreter interpreter;
  static py::module_ package = [] {
    py::module_::import("sys").attr("path").attr("insert")(0, CANALSIM_PYTHON_DIR);
    return py::module_::import("canalsim");
  }();
  return package;
}

// The compiled module's own simulate, without the DataFrame: the layer's C++ half (scenario text
// parsed, the run, the columns copied into numpy arrays).
void BM_SimulateThroughTheModule(benchmark::State& state) {
  py::module_& canalsim = canalsim_package();
  const py::object simulate = canalsim.attr("_canalsim").attr("simulate");
  const py::object text = canalsim.attr("_canalsim").attr("scenario_text")("lab");
  for (auto _ : state) {
    py::object columns = simulate(text, "lab", "op1", false, py::none());
    benchmark::DoNotOptimize(columns.ptr());
  }
}

void BM_SimulateFromPython(benchmark::State& state) {
  py::module_& canalsim = canalsim_package();
  const py::object simulate = canalsim.attr("simulate");
  for (auto _ : state) {
    py::object frame = simulate("lab", "op1");
    benchmark::DoNotOptimize(frame.ptr());
  }
}

}  // namespace

BENCHMARK(BM_SimulateFromTheLibrary)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SimulateThroughTheModule)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SimulateFromPython)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
