// Work spread over the processes of an MPI job (mpirun -n N canalsim ...) and the threads of each:
// the cases of a sweep, the trials of a blind test. Without MPI, or outside mpirun, there is one
// process and the same call runs its work on threads.
//
// One process, rank 0 (the root), hands out case indices one at a time as processes ask for them,
// so cases that differ in cost by ten times balance (dynamic load balancing); it computes cases
// too, on its own threads. Every result goes back to the root, which alone writes outputs. A case's
// result is bytes that depend only on its index: the same on one process or many, bit for bit.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace canalsim::cluster {

// The MPI job of this process for the life of the program: MPI is started when the program was
// launched by mpirun (and built with MPI) and finalised at the end. One per program, in main().
// Launched by mpirun on several processes without MPI built in, it throws InputError: each process
// would run the whole command and write the same outputs.
class Session {
 public:
  Session();
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
};

// This process's rank and the number of processes (0 and 1 outside an MPI job).
int rank();
int processes();
inline bool is_root() { return rank() == 0; }

// Whether this build can run on several processes (built with MPI), and the MPI library's name and
// version ("Open MPI v4.1.4"; empty without MPI).
bool built_with_mpi();
std::string mpi_library_version();

// Stops every process of the job after printing `message` as the program's one-line error (an
// error that only this process met, which the others would wait for forever); outside an MPI job,
// the message and exit code 1.
[[noreturn]] void abort_job(const std::string& message);

struct DistributeOptions {
  int threads = 1;                  // threads computing cases in each process; >= 1
  // Cases already computed (a resumed run): not run, their results empty. Empty: none skipped.
  std::vector<bool> skip;
  // On the root only, for each result as it arrives, one at a time, in the order cases finish:
  // for a journal of finished cases and for progress.
  std::function<void(std::size_t index, const std::string& result)> on_result;
};

// Runs work(i) for every i in [0, count) not skipped, over all processes of the job and
// options.threads threads in each. Every process must call it with the same count and skip. On the
// root, returns every result by index (empty for skipped cases); on the other processes, an empty
// vector. `work` catches its own case's failure and reports it in its result: an exception that
// escapes stops the run (rethrown on one process; abort_job in an MPI job).
std::vector<std::string> distribute(std::size_t count, const std::function<std::string(std::size_t)>& work,
                                    const DistributeOptions& options);

}  // namespace canalsim::cluster
