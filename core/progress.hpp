// Progress of anything that takes seconds: one report type for every long operation, and one
// printer that the CLI hands them to.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace canalsim {

// What a long operation says as it goes: the share done in [0, 1] (negative when it cannot tell)
// and a one-line message ("fitting LFOM to op1.csv").
struct ProgressReport {
  double fraction = -1.0;
  std::string message;
};

// Options of long operations hold one of these; empty means nobody listens. It may be called from
// several threads at once (the printer below locks).
using ProgressCallback = std::function<void(const ProgressReport&)>;

// Counts the finished items of parallel work (parallel_for, cluster::distribute) and reports
// "DONE/TOTAL LABEL" with the share done, one report at a time whichever thread finished. Without
// a callback it does nothing.
class ProgressCounter {
 public:
  // `already_done`: items finished before (a resumed run), counted from there.
  ProgressCounter(ProgressCallback progress, std::size_t total, std::size_t already_done = 0)
      : progress_(std::move(progress)), total_(total), done_(already_done) {}
  // One more item finished; `label` says what ("trials", "fits (LFOM to op1.csv)").
  void finished(const std::string& label);

 private:
  ProgressCallback progress_;
  std::size_t total_;
  std::size_t done_ = 0;
  std::mutex mutex_;
};

// A progress line on stderr, "LABEL [  3.2 s]: 42% message": on a terminal rewritten in place, the
// first report at once and then at most 10 times a second; on a pipe or file a line once the work
// has run 1.5 s and then every 5 s, so logs stay readable and short commands print nothing. A
// heartbeat thread repeats the last report when the work says nothing for a while (a long Newton
// solve), so no run longer than 1.5 s is silent. `force` shows a report (a stage change) whatever
// the timing.
class ProgressLine {
 public:
  explicit ProgressLine(std::string label);
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;
  ~ProgressLine();

  void report(const ProgressReport& report, bool force = false);
  // A callback that forwards to report(); valid while this object lives.
  ProgressCallback callback();
  // Stops the heartbeat and ends the in-place line on a terminal (called by the destructor).
  void finish();

 private:
  void show(bool force);  // with mutex_ held
  void beat();            // the heartbeat thread

  std::mutex mutex_;
  std::condition_variable wake_;
  std::string label_;
  bool tty_;
  bool shown_ = false;
  bool stopped_ = false;
  ProgressReport last_report_{0.0, ""};
  std::chrono::steady_clock::time_point start_, last_;
  std::thread heartbeat_;  // last: starts once everything above is ready
};

}  // namespace canalsim
