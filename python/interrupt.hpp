// Long calls from Python: the work runs without the GIL, its progress reaches an optional Python
// callable, and Ctrl-C stops it. Python runs its own signal handlers only on the main thread and
// only between bytecodes, neither of which happens while the main thread waits in C++ for worker
// threads, so for the duration of the call SIGINT sets a flag that every progress report checks;
// the work then unwinds through the library (its parallel loops rethrow, its outputs are written
// all or nothing) and KeyboardInterrupt is raised when the call returns. An exception of the
// callable stops the work the same way and is raised again.
#pragma once

#include <atomic>
#include <mutex>
#include <optional>

#include <pybind11/pybind11.h>

#include "core/progress.hpp"

namespace canalsim::python {

class LongCall {
 public:
  // `progress`: None, or a callable taking (fraction, message); fraction is in [0, 1], or −1
  // when the work cannot tell.
  explicit LongCall(pybind11::object progress);
  LongCall(const LongCall&) = delete;
  LongCall& operator=(const LongCall&) = delete;

  // For the library's options: reports to the callable and stops the work when asked to.
  ProgressCallback callback();

  // Runs `work` without the GIL, with SIGINT caught; raises KeyboardInterrupt or the callable's
  // exception when the work was stopped (or Ctrl-C came after its last report: the user asked to
  // stop, and a result after that would surprise).
  template <class Work>
  auto run(Work work) -> decltype(work()) {
    std::optional<decltype(work())> result;
    {
      SigintScope sigint;
      pybind11::gil_scoped_release release;
      try {
        result.emplace(work());
      } catch (const Stopped&) {
      }
    }
    if (!result || interrupted()) raise_why_stopped();
    return std::move(*result);
  }

 private:
  struct Stopped {};  // thrown through the library to unwind it
  // SIGINT sets a flag while it lives; the previous handler is restored after.
  class SigintScope {
   public:
    SigintScope();
    ~SigintScope();
    SigintScope(const SigintScope&) = delete;
    SigintScope& operator=(const SigintScope&) = delete;
  };

  void report(const ProgressReport& report);
  bool interrupted() const;
  [[noreturn]] void raise_why_stopped();

  pybind11::object progress_;
  std::mutex mutex_;              // one report at a time reaches the callable
  std::atomic<bool> stopped_{false};
  std::optional<pybind11::error_already_set> error_;  // the callable's exception
};

}  // namespace canalsim::python
