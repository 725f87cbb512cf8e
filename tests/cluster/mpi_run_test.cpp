// The program under `mpirun -n 2` (Open MPI; --oversubscribe, and --allow-run-as-root where the
// tests run as root) against one process: the same trials, bit for bit but their timings, and the
// commands that cannot share their work refused in one line.
#include <filesystem>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "testing/cli_run.hpp"

namespace canalsim::cli_test {
namespace {

// mpirun with two processes on this machine, whatever its cores and user; the sanitizers' leak
// check off in the ranks (Open MPI's own allocations live until exit).
std::string mpirun_two() {
  std::string command = std::string(CANALSIM_MPIRUN) + " --oversubscribe -n 2 -x ASAN_OPTIONS=detect_leaks=0";
  if (::geteuid() == 0) command += " --allow-run-as-root";
  return command;
}

RunResult run_under_mpirun(const std::string& arguments, const fs::path& scratch) {
  const fs::path err = scratch / "stderr.txt", out = scratch / "stdout.txt";
  const std::string command = "cd '" + scratch.string() + "' && " + mpirun_two() + " " + std::string(CANALSIM_PROGRAM) +
                              " " + arguments + " > " + out.string() + " 2> " + err.string();
  RunResult r;
  r.status = std::system(command.c_str());
  r.code = WIFEXITED(r.status) ? WEXITSTATUS(r.status) : -1;
  r.err = read_text(err);
  r.out = read_text(out);
  return r;
}

// The blind test's JSON without what depends on the machine's speed.
nlohmann::json without_timings(nlohmann::json j) {
  j.erase("seconds");
  j.erase("mean_trial_seconds");
  for (auto& trial : j.at("trials")) {
    for (const char* key : {"seconds", "simulation_seconds", "calibration_seconds"}) trial.erase(key);
  }
  return j;
}

std::string report_without_timings(const std::string& report) {
  std::istringstream lines(report);
  std::string kept;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("time ", 0) != 0 && line.rfind("wrote ", 0) != 0) kept += line + '\n';
  }
  return kept;
}

TEST(MpiRun, BlindtestOnTwoProcessesGivesTheTrialsOfOne) {
  const fs::path dir = scratch_dir("mpi_blindtest");
  const std::string arguments = "blindtest --trials 4 --seed 5 --duration 20 --experiments op1 --threads 1 --json ";
  const RunResult one = run_canalsim(arguments + "one.json", dir);
  ASSERT_EQ(one.code, 0) << one.err;
  const RunResult two = run_under_mpirun(arguments + "two.json", dir);
  ASSERT_EQ(two.code, 0) << two.err;
  const auto a = without_timings(nlohmann::json::parse(read_text(dir / "one.json")));
  const auto b = without_timings(nlohmann::json::parse(read_text(dir / "two.json")));
  ASSERT_EQ(a.at("trials").size(), 4u);
  EXPECT_EQ(a, b);
  // Rank 0 alone prints: one report, not two, the same but for its timings and file name.
  EXPECT_EQ(report_without_timings(two.out), report_without_timings(one.out));
  fs::remove_all(dir);
}

TEST(MpiRun, ACommandThatCannotShareItsWorkIsRefusedInOneLine) {
  const fs::path dir = scratch_dir("mpi_refused");
  const RunResult r = run_under_mpirun("simulate --scenario lab --experiment op1 -o op1.csv", dir);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("canalsim: error: canalsim simulate runs on one process, not 2: expected mpirun only with "
                       "sweep or blindtest"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "op1.csv"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace canalsim::cli_test
