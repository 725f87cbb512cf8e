// One diagnosis of four 255.5 s laboratory recordings (op1–op4) with the whole catalog, on two
// threads, as `canalsim diagnose --scenario lab op1.csv op2.csv op3.csv op4.csv` runs it. The
// recordings carry a concealed gate leakage of 1.5 mm so that every candidate is really fitted.
// Issue 5's target: at most 60 s.
#include <benchmark/benchmark.h>

#include "diagnosis/blindtest.hpp"
#include "diagnosis/diagnose.hpp"
#include "scenarios/builtin.hpp"
#include "scenarios/simulate.hpp"

namespace {

using namespace canalsim;

std::vector<Recording> lab_recordings(const scenarios::Scenario& lab) {
  std::vector<Recording> out;
  for (const char* name : {"op1", "op2", "op3", "op4"}) {
    scenarios::Scenario s = lab;
    scenarios::ExperimentSpec e = *lab.find_experiment(name);
    scenarios::SensorSpec sensors = s.sensors;
    sensors.noise_std_mm = 0.05;
    e.sensors = sensors;
    diagnosis::conceal({"gate_leakage", 1.5}, s, e, 0.0);
    Recording r = scenarios::simulate(s, e);
    r.source = std::string(name) + ".csv";
    out.push_back(std::move(r));
  }
  return out;
}

void BM_DiagnoseFourLabRecordings(benchmark::State& state) {
  const auto lab = scenarios::builtin_scenario("lab");
  const auto recordings = lab_recordings(lab);
  diagnosis::DiagnoseOptions options;
  options.threads = static_cast<int>(state.range(0));
  std::string verdict;
  for (auto _ : state) {
    const auto d = diagnosis::diagnose(lab, recordings, options);
    verdict = d.verdict;
    benchmark::DoNotOptimize(d.effects.data());
  }
  state.SetLabel("verdict " + verdict);
}

BENCHMARK(BM_DiagnoseFourLabRecordings)->Arg(2)->Arg(1)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
