// Simulation warnings passed on once per recording (calibrate.cpp).
#pragma once

#include <cstdio>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace canalsim::calibration {

// Simulation warnings (a failed steady state, scenarios/simulate.hpp) passed on once per
// recording — to the caller's ReplayOptions::warning, else to stderr — and kept for the result:
// a calibration simulates every recording hundreds of times, and the same warning each time
// would bury the terminal. Called from the parallel simulations.
class WarningOncePerRecording {
 public:
  explicit WarningOncePerRecording(std::function<void(const std::string&)> sink) : sink_(std::move(sink)) {}
  void operator()(const std::string& message) {
    // "<scenario>: experiment <recording>: the steady state (Newton) failed (...)": one per recording.
    const std::string recording = message.substr(0, message.find(": the "));
    {
      const std::lock_guard lock(mutex_);
      if (!seen_.insert(recording).second) return;
      kept_.push_back(message);
    }
    if (sink_) {
      sink_(message);
    } else {
      std::fprintf(stderr, "canalsim: warning: %s\n", message.c_str());
    }
  }
  std::vector<std::string> kept() {
    const std::lock_guard lock(mutex_);
    return kept_;
  }

 private:
  std::function<void(const std::string&)> sink_;
  std::mutex mutex_;
  std::set<std::string> seen_;
  std::vector<std::string> kept_;
};

}  // namespace canalsim::calibration
