// A progress line on stderr for anything that takes more than a moment: "label: 42%" rewritten in
// place on a terminal; on a pipe or file only the final line, so logs stay readable.
#pragma once

#include <cstdio>
#include <string>
#include <unistd.h>

namespace canalsim::cli {

class Progress {
 public:
  explicit Progress(std::string label) : label_(std::move(label)), tty_(::isatty(STDERR_FILENO) != 0) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { finish(); }

  // fraction in [0, 1]; redraws only when the whole percentage changes.
  void update(double fraction) {
    const int percent = static_cast<int>(fraction * 100.0 + 1e-9);
    if (percent == last_ || !tty_) return;
    last_ = percent;
    std::fprintf(stderr, "\r%s: %3d%%", label_.c_str(), percent);
    std::fflush(stderr);
  }
  void finish() {
    if (done_) return;
    done_ = true;
    if (tty_) std::fprintf(stderr, "\r%s: done\n", label_.c_str());
  }

 private:
  std::string label_;
  bool tty_;
  int last_ = -1;
  bool done_ = false;
};

}  // namespace canalsim::cli
