#include "core/progress.hpp"

#include <cstdio>
#include <unistd.h>

namespace canalsim {

ProgressLine::ProgressLine(std::string label)
    : label_(std::move(label)), tty_(::isatty(STDERR_FILENO) != 0), start_(std::chrono::steady_clock::now()) {}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::report(const ProgressReport& report, bool force) {
  const std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  // A terminal shows the first report at once and then at most 10 a second; a log gets a line
  // only once the work has run 5 s, and then every 5 s, so short commands leave logs clean.
  const auto gap = tty_ ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  const auto since = shown_ ? last_ : start_;
  if (!force && (shown_ || !tty_) && now - since < gap) return;
  last_ = now;
  shown_ = true;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::string text = report.message;
  if (report.fraction >= 0.0) {
    const int percent = static_cast<int>(100.0 * std::min(report.fraction, 1.0) + 1e-9);
    text = std::to_string(percent) + "%" + (text.empty() ? "" : " " + text);
  }
  if (tty_) {
    std::fprintf(stderr, "\r\033[K%s [%5.1f s]: %.90s", label_.c_str(), elapsed, text.c_str());
  } else {
    std::fprintf(stderr, "%s [%5.1f s]: %s\n", label_.c_str(), elapsed, text.c_str());
  }
  std::fflush(stderr);
}

ProgressCallback ProgressLine::callback() {
  return [this](const ProgressReport& r) { report(r); };
}

void ProgressLine::finish() {
  const std::lock_guard lock(mutex_);
  if (tty_ && shown_) std::fprintf(stderr, "\n");
  shown_ = false;
}

}  // namespace canalsim
