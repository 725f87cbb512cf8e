#include "cluster/distribute.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <exception>
#include <iostream>
#include <mutex>
#include <thread>

#include "core/errors.hpp"

#ifdef CANALSIM_HAVE_MPI
#define OMPI_SKIP_MPICXX 1   // the C interface only: the C++ bindings (removed in MPI-3) need their own library
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace canalsim::cluster {
namespace {

#ifdef CANALSIM_HAVE_MPI
bool g_mpi_started = false;
#endif

// The environment mpirun gives its processes (Open MPI; PMI and PMIx of other launchers).
int processes_launched() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"}) {
    if (const char* value = std::getenv(name)) return std::max(1, std::atoi(value));
  }
  return std::getenv("PMIX_RANK") ? 2 : 1;  // PMIx without a size: some launcher, size unknown
}

// The cases of one process: `threads` threads take indices from a queue that the process's main
// thread fills, and leave results for it. Only the main thread talks to other processes (MPI's
// "funneled" threading).
class LocalPool {
 public:
  LocalPool(int threads, const std::function<std::string(std::size_t)>& work) : work_(work) {
    for (int t = 0; t < threads; ++t) threads_.emplace_back([this] { run(); });
  }
  ~LocalPool() {
    {
      const std::lock_guard lock(mutex_);
      closing_ = true;
    }
    wake_workers_.notify_all();
    for (auto& t : threads_) t.join();
  }
  LocalPool(const LocalPool&) = delete;
  LocalPool& operator=(const LocalPool&) = delete;

  int capacity() const { return static_cast<int>(threads_.size()); }

  void submit(std::size_t index) {
    {
      const std::lock_guard lock(mutex_);
      queued_.push_back(index);
      ++in_flight_;
    }
    wake_workers_.notify_one();
  }
  int in_flight() {
    const std::lock_guard lock(mutex_);
    return in_flight_;
  }

  struct Finished {
    std::size_t index = 0;
    std::string result;
    std::exception_ptr error;
  };
  // The results finished since the last call; waits up to `wait` for one when there is none.
  std::vector<Finished> collect(std::chrono::milliseconds wait) {
    std::unique_lock lock(mutex_);
    if (finished_.empty()) wake_main_.wait_for(lock, wait, [this] { return !finished_.empty(); });
    std::vector<Finished> out(std::make_move_iterator(finished_.begin()), std::make_move_iterator(finished_.end()));
    finished_.clear();
    in_flight_ -= static_cast<int>(out.size());
    return out;
  }

 private:
  void run() {
    for (;;) {
      std::size_t index = 0;
      {
        std::unique_lock lock(mutex_);
        wake_workers_.wait(lock, [this] { return closing_ || !queued_.empty(); });
        if (queued_.empty()) return;
        index = queued_.front();
        queued_.pop_front();
      }
      Finished done{index, {}, nullptr};
      try {
        done.result = work_(index);
      } catch (...) {
        done.error = std::current_exception();
      }
      {
        const std::lock_guard lock(mutex_);
        finished_.push_back(std::move(done));
      }
      wake_main_.notify_one();
    }
  }

  const std::function<std::string(std::size_t)>& work_;
  std::mutex mutex_;
  std::condition_variable wake_workers_, wake_main_;
  std::deque<std::size_t> queued_;
  std::vector<Finished> finished_;
  int in_flight_ = 0;
  bool closing_ = false;
  std::vector<std::thread> threads_;  // last: started once the rest is ready
};

// The indices still to compute, in increasing order.
class Cursor {
 public:
  Cursor(std::size_t count, const std::vector<bool>& skip) : count_(count), skip_(skip) { advance(); }
  bool done() const { return next_ >= count_; }
  std::size_t take() {
    const std::size_t index = next_++;
    advance();
    return index;
  }

 private:
  void advance() {
    while (next_ < count_ && next_ < skip_.size() && skip_[next_]) ++next_;
  }
  std::size_t count_;
  const std::vector<bool>& skip_;
  std::size_t next_ = 0;
};

std::string error_text(const std::exception_ptr& error) {
  try {
    std::rethrow_exception(error);
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown exception";
  }
}

constexpr auto kPoll = std::chrono::milliseconds(2);  // the root's wait between looks at its mail

#ifdef CANALSIM_HAVE_MPI
// Messages between the root and the other processes: a request for a case, the case's index
// (-1: no more), and a result (its index's 8 bytes, then the result's bytes).
enum Tag : int { kRequest = 1, kAssign = 2, kResult = 3 };

void send_result(std::size_t index, const std::string& result) {
  std::string message(sizeof(std::uint64_t), '\0');
  const auto index64 = static_cast<std::uint64_t>(index);
  std::copy_n(reinterpret_cast<const char*>(&index64), sizeof index64, message.begin());
  message += result;
  MPI_Send(message.data(), static_cast<int>(message.size()), MPI_BYTE, 0, kResult, MPI_COMM_WORLD);
}

// A process other than the root: asks for a case whenever a thread is free, sends each result back.
void serve_cases(LocalPool& pool) {
  bool more = true;
  for (;;) {
    while (more && pool.in_flight() < pool.capacity()) {
      MPI_Send(nullptr, 0, MPI_BYTE, 0, kRequest, MPI_COMM_WORLD);
      std::int64_t index = -1;
      MPI_Recv(&index, 1, MPI_INT64_T, 0, kAssign, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (index < 0) {
        more = false;
      } else {
        pool.submit(static_cast<std::size_t>(index));
      }
    }
    if (!more && pool.in_flight() == 0) return;
    for (auto& f : pool.collect(std::chrono::milliseconds(1000))) {
      if (f.error) abort_job("rank " + std::to_string(rank()) + ": " + error_text(f.error));
      send_result(f.index, f.result);
    }
  }
}
#endif

}  // namespace

Session::Session() {
  const int launched = processes_launched();
#ifdef CANALSIM_HAVE_MPI
  if (launched > 1 || std::getenv("OMPI_COMM_WORLD_SIZE")) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    g_mpi_started = true;
  }
#else
  if (launched > 1) {
    throw InputError("canalsim was built without MPI: under mpirun each of the " + std::to_string(launched) +
                     " processes would run the whole command; expected one process (build with libopenmpi-dev "
                     "installed to run on several)");
  }
#endif
}

Session::~Session() {
#ifdef CANALSIM_HAVE_MPI
  if (g_mpi_started) MPI_Finalize();
  g_mpi_started = false;
#endif
}

int rank() {
#ifdef CANALSIM_HAVE_MPI
  if (g_mpi_started) {
    int r = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &r);
    return r;
  }
#endif
  return 0;
}

int processes() {
#ifdef CANALSIM_HAVE_MPI
  if (g_mpi_started) {
    int n = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &n);
    return n;
  }
#endif
  return 1;
}

bool built_with_mpi() {
#ifdef CANALSIM_HAVE_MPI
  return true;
#else
  return false;
#endif
}

std::string mpi_library_version() {
#ifdef CANALSIM_HAVE_MPI
  char text[MPI_MAX_LIBRARY_VERSION_STRING] = {};
  int length = 0;
  MPI_Get_library_version(text, &length);  // allowed before MPI_Init (MPI 3.1, 8.1.1)
  const std::string full(text, static_cast<std::size_t>(length));
  return full.substr(0, full.find_first_of(",\n"));
#else
  return "";
#endif
}

void abort_job(const std::string& message) {
  std::cerr << "canalsim: error: " << message << '\n' << std::flush;
#ifdef CANALSIM_HAVE_MPI
  if (g_mpi_started) MPI_Abort(MPI_COMM_WORLD, 1);
#endif
  std::exit(1);
}

std::vector<std::string> distribute(std::size_t count, const std::function<std::string(std::size_t)>& work,
                                    const DistributeOptions& options) {
  LocalPool pool(std::max(1, options.threads), work);
#ifdef CANALSIM_HAVE_MPI
  if (!is_root()) {
    serve_cases(pool);
    return {};
  }
#endif

  // The root: its own threads and the other processes' requests both draw from one cursor.
  std::vector<std::string> results(count);
  Cursor cursor(count, options.skip);
  std::exception_ptr first_error;
  std::size_t first_error_index = count;
  const auto receive = [&](std::size_t index, std::string result) {
    results[index] = std::move(result);
    if (options.on_result) options.on_result(index, results[index]);
  };
  int others_asking = processes() - 1;  // processes not yet told that no case is left
  std::size_t with_others = 0;           // cases handed to other processes, their results not back
  while (!cursor.done() || pool.in_flight() > 0 || others_asking > 0 || with_others > 0) {
    while (!cursor.done() && pool.in_flight() < pool.capacity()) pool.submit(cursor.take());
#ifdef CANALSIM_HAVE_MPI
    while (g_mpi_started) {
      int waiting = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &waiting, &status);
      if (!waiting) break;
      if (status.MPI_TAG == kRequest) {
        MPI_Recv(nullptr, 0, MPI_BYTE, status.MPI_SOURCE, kRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        const std::int64_t index = cursor.done() ? -1 : static_cast<std::int64_t>(cursor.take());
        if (index < 0) --others_asking;
        else ++with_others;
        MPI_Send(&index, 1, MPI_INT64_T, status.MPI_SOURCE, kAssign, MPI_COMM_WORLD);
      } else {
        int size = 0;
        MPI_Get_count(&status, MPI_BYTE, &size);
        std::string message(static_cast<std::size_t>(size), '\0');
        MPI_Recv(message.data(), size, MPI_BYTE, status.MPI_SOURCE, kResult, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        std::uint64_t index = 0;
        std::copy_n(message.data(), sizeof index, reinterpret_cast<char*>(&index));
        --with_others;
        receive(static_cast<std::size_t>(index), message.substr(sizeof index));
      }
    }
#endif
    for (auto& f : pool.collect(kPoll)) {
      if (f.error) {
        if (processes() > 1) abort_job(error_text(f.error));
        if (f.index < first_error_index) first_error = f.error, first_error_index = f.index;
        continue;
      }
      receive(f.index, std::move(f.result));
    }
  }
  if (first_error) std::rethrow_exception(first_error);
  return results;
}

}  // namespace canalsim::cluster
