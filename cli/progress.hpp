// A progress line on stderr for anything that takes more than a moment (core/progress.hpp's
// ProgressLine: rewritten in place on a terminal, a line at most every 5 s on a pipe or file).
// Nothing is printed for work done within 1.5 s; anything longer shows a line by then even when
// the work reports nothing for a while (a long Newton solve, a long first step), so that no run
// is silent for minutes: a heartbeat thread repeats the last report.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "core/progress.hpp"

namespace canalsim::cli {

class Progress {
 public:
  explicit Progress(std::string label)
      : line_(std::move(label)), start_(std::chrono::steady_clock::now()), heartbeat_([this] { beat(); }) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { finish(); }

  // fraction in [0, 1].
  void update(double fraction) {
    std::unique_lock lock(mutex_);
    last_.fraction = fraction;
    if (done_ || std::chrono::steady_clock::now() - start_ < kQuiet) return;
    const ProgressReport report = last_;
    lock.unlock();
    line_.report(report);
  }
  void finish() {
    {
      const std::lock_guard lock(mutex_);
      if (done_) return;
      done_ = true;
    }
    wake_.notify_all();
    heartbeat_.join();
    line_.finish();
  }

 private:
  static constexpr std::chrono::milliseconds kQuiet{1500};

  void beat() {
    std::unique_lock lock(mutex_);
    if (wake_.wait_for(lock, kQuiet, [this] { return done_; })) return;
    while (!done_) {
      const ProgressReport report = last_;
      lock.unlock();
      line_.report(report);
      lock.lock();
      wake_.wait_for(lock, std::chrono::seconds(1), [this] { return done_; });
    }
  }

  ProgressLine line_;
  std::mutex mutex_;
  std::condition_variable wake_;
  ProgressReport last_{0.0, ""};
  bool done_ = false;
  std::chrono::steady_clock::time_point start_;
  std::thread heartbeat_;
};

}  // namespace canalsim::cli
