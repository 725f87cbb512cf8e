// The program under `mpirun -n 2` (Open MPI; --oversubscribe, and --allow-run-as-root where the
// tests run as root) against one process: the same trials, bit for bit but their timings, and the
// commands that cannot share their work refused in one line.
#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

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

// A sweep of 8 cases, each a fit of about a second under the sanitizers: long enough to be killed
// in the middle.
constexpr const char* kSweep = R"(scenario = "lab"
experiments = ["op1"]
duration_s = 40
[[vary]]
key = "pools[1].length_m"
values = [3.5, 4.0, 4.5, 5.0]
[[vary]]
key = "pools[1].manning_n"
values = [0.010, 0.013]
[compute]
summary = true
fit = ["LIOM"]
)";

// The same sweep with 24 cases: enough left to run after the kill that it lands halfway, where
// the 8 cases above can all finish between the journal's second case and the kill.
constexpr const char* kLongerSweep = R"(scenario = "lab"
experiments = ["op1"]
duration_s = 40
[[vary]]
key = "pools[1].length_m"
values = [3.0, 3.5, 4.0, 4.5, 5.0, 5.5]
[[vary]]
key = "pools[1].manning_n"
values = [0.010, 0.011, 0.012, 0.013]
[compute]
summary = true
fit = ["LIOM"]
)";
constexpr std::size_t kLongerSweepCases = 24;

std::size_t lines_in(const fs::path& file) { return fs::exists(file) ? count_lines(read_text(file)) : 0; }

// The process of rank `rank` of the job writing into `out`: Open MPI tells each its rank in the
// environment (OMPI_COMM_WORLD_RANK).
int pid_of_rank(int rank, const std::string& out) {
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string command_line = read_text(entry.path() / "cmdline");
    std::replace(command_line.begin(), command_line.end(), '\0', ' ');
    if (command_line.find(" sweep ") == std::string::npos || command_line.find(out) == std::string::npos) continue;
    std::string environment = read_text(entry.path() / "environ");
    std::replace(environment.begin(), environment.end(), '\0', '\n');
    if (("\n" + environment).find("\nOMPI_COMM_WORLD_RANK=" + std::to_string(rank) + "\n") != std::string::npos) {
      return std::stoi(name);
    }
  }
  return -1;
}

TEST(MpiRun, SweepOnTwoProcessesWritesTheTableOfOne) {
  const fs::path dir = scratch_dir("mpi_sweep");
  std::ofstream(dir / "small.toml") << kSweep;
  const RunResult one = run_canalsim("sweep small.toml --out one", dir);
  ASSERT_EQ(one.code, 0) << one.err;
  const RunResult two = run_under_mpirun("sweep small.toml --out two", dir);
  ASSERT_EQ(two.code, 0) << two.err;
  const std::string table = read_text(dir / "one" / "table.csv");
  EXPECT_EQ(count_lines(table), 9u);  // the header and 8 cases
  EXPECT_EQ(read_text(dir / "two" / "table.csv"), table);
  EXPECT_EQ(read_text(dir / "two" / "sweep.toml"), read_text(dir / "one" / "sweep.toml"));
  fs::remove_all(dir);
}

// A rank killed halfway: the job ends, the journal holds the cases finished, no table is
// written, and --resume completes a table identical to an uninterrupted run's.
TEST(MpiRun, ASweepWhoseRankIsKilledIsCompletedByResume) {
  const fs::path dir = scratch_dir("mpi_sweep_killed");
  std::ofstream(dir / "small.toml") << kLongerSweep;
  const RunResult whole = run_canalsim("sweep small.toml --out whole", dir);
  ASSERT_EQ(whole.code, 0) << whole.err;

  const fs::path out = dir / "killed";
  const fs::path journal = out / "table.partial.csv";
  std::thread job([&] { run_under_mpirun("sweep small.toml --out " + out.string(), dir); });
  // Two header lines, then a row per finished case: kill rank 1 once two cases are in.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  int victim = -1;
  while (std::chrono::steady_clock::now() < give_up && !fs::exists(out / "table.csv")) {
    if (lines_in(journal) >= 4 && (victim = pid_of_rank(1, out.string())) > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GT(victim, 0) << "the job ended or never got going before a rank could be killed";
  ::kill(victim, SIGKILL);
  job.join();
  EXPECT_FALSE(fs::exists(out / "table.csv")) << "a table from a job that lost a rank";
  const std::size_t journalled = lines_in(journal);
  EXPECT_GE(journalled, 4u);
  EXPECT_LT(journalled, 2 + kLongerSweepCases) << "every case was finished before the kill";

  const RunResult resumed = run_canalsim("sweep small.toml --out killed --resume", dir);
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_EQ(read_text(out / "table.csv"), read_text(dir / "whole" / "table.csv"));
  EXPECT_FALSE(fs::exists(journal));
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
