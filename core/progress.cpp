#include "core/progress.hpp"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace canalsim {
namespace {

// A log (pipe or file) gets its first line once the work has run this long, so short commands
// leave it clean and no run is silent past two seconds.
constexpr std::chrono::milliseconds kQuiet{1500};

}  // namespace

void ProgressCounter::finished(const std::string& label) {
  if (!progress_) return;
  const std::lock_guard lock(mutex_);
  ++done_;
  progress_({total_ > 0 ? static_cast<double>(done_) / static_cast<double>(total_) : 1.0,
             std::to_string(done_) + "/" + std::to_string(total_) + " " + label});
}

ProgressLine::ProgressLine(std::string label)
    : label_(std::move(label)),
      tty_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      heartbeat_([this] { beat(); }) {}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::report(const ProgressReport& report, bool force) {
  const std::lock_guard lock(mutex_);
  last_report_ = report;
  show(force);
}

// Called with the mutex held.
void ProgressLine::show(bool force) {
  const auto now = std::chrono::steady_clock::now();
  // A terminal shows the first report at once and then at most 10 a second; a log gets a line
  // once the work has run 1.5 s, and then every 5 s, so short commands leave logs clean.
  const auto gap = tty_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  if (!force && (shown_ ? now - last_ < gap : (!tty_ && now - start_ < kQuiet))) return;
  last_ = now;
  shown_ = true;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::string text = last_report_.message;
  if (last_report_.fraction >= 0.0) {
    const int percent = static_cast<int>(100.0 * std::min(last_report_.fraction, 1.0) + 1e-9);
    text = std::to_string(percent) + "%" + (text.empty() ? "" : " " + text);
  }
  if (tty_) {
    std::fprintf(stderr, "\r\033[K%s [%5.1f s]: %.90s", label_.c_str(), elapsed, text.c_str());
  } else {
    std::fprintf(stderr, "%s [%5.1f s]: %s\n", label_.c_str(), elapsed, text.c_str());
  }
  std::fflush(stderr);
}

// The work may report nothing for a long time (a Newton solve, a long first step): the heartbeat
// repeats the last report (with the elapsed time) so that the line appears within 1.5 s and a
// stuck-looking run still shows it is alive.
void ProgressLine::beat() {
  std::unique_lock lock(mutex_);
  if (wake_.wait_for(lock, kQuiet, [this] { return stopped_; })) return;
  while (!stopped_) {
    const auto now = std::chrono::steady_clock::now();
    const auto gap = tty_ ? std::chrono::milliseconds(1000) : std::chrono::milliseconds(5000);
    if (!shown_ || now - last_ >= gap) show(true);
    wake_.wait_for(lock, std::chrono::milliseconds(500), [this] { return stopped_; });
  }
}

ProgressCallback ProgressLine::callback() {
  return [this](const ProgressReport& r) { report(r); };
}

void ProgressLine::finish() {
  {
    const std::lock_guard lock(mutex_);
    if (stopped_) return;
    stopped_ = true;
  }
  wake_.notify_all();
  if (heartbeat_.joinable()) heartbeat_.join();
  const std::lock_guard lock(mutex_);
  if (tty_ && shown_) std::fprintf(stderr, "\n");
  shown_ = false;
}

}  // namespace canalsim
