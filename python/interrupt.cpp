#include "python/interrupt.hpp"

#include <csignal>

namespace canalsim::python {
namespace {

// Set by SIGINT during a long call; read by every progress report.
std::atomic<bool> g_sigint{false};
struct sigaction g_previous_sigint {};

void on_sigint(int) { g_sigint.store(true); }

}  // namespace

namespace py = pybind11;

LongCall::LongCall(py::object progress) : progress_(std::move(progress)) {}

LongCall::SigintScope::SigintScope() {
  g_sigint.store(false);
  struct sigaction action {};
  action.sa_handler = on_sigint;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &g_previous_sigint);
}

LongCall::SigintScope::~SigintScope() { ::sigaction(SIGINT, &g_previous_sigint, nullptr); }

ProgressCallback LongCall::callback() {
  return [this](const ProgressReport& r) { report(r); };
}

void LongCall::report(const ProgressReport& r) {
  if (g_sigint.load()) stopped_.store(true);
  if (stopped_.load()) throw Stopped{};
  if (progress_.is_none()) return;
  const std::lock_guard<std::mutex> lock(mutex_);
  if (stopped_.load()) throw Stopped{};
  py::gil_scoped_acquire gil;
  try {
    progress_(r.fraction, r.message);
  } catch (py::error_already_set& e) {
    error_.emplace(std::move(e));
    stopped_.store(true);
    throw Stopped{};
  }
}

bool LongCall::interrupted() const { return g_sigint.load() || stopped_.load(); }

void LongCall::raise_why_stopped() {
  if (error_) {
    error_->restore();
    error_.reset();
    throw py::error_already_set();
  }
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw py::error_already_set();
}

}  // namespace canalsim::python
