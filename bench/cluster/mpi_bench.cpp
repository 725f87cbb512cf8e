// `mpirun -n 2 canalsim blindtest` against one process on one thread, and against one process on
// two threads, the blind test's trials and seed the same. The machine is shared: each iteration
// runs the single process and the MPI job one after the other, in alternating order, and the
// speed-up is the ratio of the two sums. Wall times of whole programs, so MPI's start-up and
// rank 0's collection of the results are in them.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <unistd.h>

namespace {

const std::string kBlindtest =
    " blindtest --trials 12 --seed 3 --experiments op1,op3 --duration 60 > /dev/null 2>&1";

std::string mpirun_two() {
  std::string command = std::string(CANALSIM_MPIRUN) + " --oversubscribe -n 2";
  if (::geteuid() == 0) command += " --allow-run-as-root";
  return command + " " + CANALSIM_PROGRAM + kBlindtest + " --threads 1";
}

double seconds_of(const std::string& command) {
  const auto start = std::chrono::steady_clock::now();
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Argument: the threads of the single process (1: the same cores as the job's ranks use, one each;
// 2: the threads canalsim uses by default on this machine).
void BM_BlindtestTwoProcessesAgainstOne(benchmark::State& state) {
  const std::string one_process = std::string(CANALSIM_PROGRAM) + kBlindtest + " --threads " + std::to_string(state.range(0));
  const std::string two_processes = mpirun_two();
  double one_seconds = 0.0, two_seconds = 0.0;
  bool one_first = true;
  for (auto _ : state) {
    if (one_first) {
      one_seconds += seconds_of(one_process);
      two_seconds += seconds_of(two_processes);
    } else {
      two_seconds += seconds_of(two_processes);
      one_seconds += seconds_of(one_process);
    }
    one_first = !one_first;
  }
  const double runs = static_cast<double>(state.iterations());
  state.counters["one_process_s"] = one_seconds / runs;
  state.counters["two_processes_s"] = two_seconds / runs;
  state.counters["speedup"] = one_seconds / two_seconds;
}

}  // namespace

BENCHMARK(BM_BlindtestTwoProcessesAgainstOne)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(2)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_MAIN();
