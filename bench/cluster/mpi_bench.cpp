// `mpirun -n 2 canalsim blindtest` against one process on one thread, and against one process on
// two threads, the blind test's trials and seed the same. The machine is shared: each iteration
// runs the single process and the MPI job one after the other, in alternating order, and the
// speed-up is the ratio of the two sums. Wall times of whole programs, so MPI's start-up and
// rank 0's collection of the results are in them.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include "testing/paired_timing.hpp"

namespace {

const std::string kBlindtest =
    " blindtest --trials 12 --seed 3 --experiments op1,op3 --duration 60 > /dev/null 2>&1";

std::string mpirun_two() {
  std::string command = std::string(CANALSIM_MPIRUN) + " --oversubscribe -n 2";
  if (::geteuid() == 0) command += " --allow-run-as-root";
  return command + " " + CANALSIM_PROGRAM + kBlindtest + " --threads 1";
}

// Argument: the threads of the single process (1: the same cores as the job's ranks use, one each;
// 2: the threads canalsim uses by default on this machine).
void BM_BlindtestTwoProcessesAgainstOne(benchmark::State& state) {
  const std::string one_process = std::string(CANALSIM_PROGRAM) + kBlindtest + " --threads " + std::to_string(state.range(0));
  const std::string two_processes = mpirun_two();
  const auto run = [](const std::string& command) {
    if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  };
  const canalsim::testing::PairedSeconds seconds = canalsim::testing::time_in_alternating_pairs(
      state, [&] { run(one_process); }, [&] { run(two_processes); });
  state.counters["one_process_s"] = seconds.first;
  state.counters["two_processes_s"] = seconds.second;
  state.counters["speedup"] = seconds.first / seconds.second;
}

}  // namespace

BENCHMARK(BM_BlindtestTwoProcessesAgainstOne)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(2)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_MAIN();
