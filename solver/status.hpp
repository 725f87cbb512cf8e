// Status: the result of an operation that can fail for numerical or input reasons. Failure is a
// returned value with a one-line message, never an abort (docs/architecture.md). A failed step also names
// where it happened (time, reach, cell) so that callers can report it.
#pragma once

#include <string>
#include <utility>

namespace canalsim::solver {

class Status {
 public:
  Status() = default;  // ok
  static Status ok() { return Status(); }
  static Status error(std::string message) { return Status(std::move(message)); }
  // A failure located in the simulation: time [s], reach index and cell index.
  static Status error_at(std::string message, double time_s, int reach, int cell);

  bool is_ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const std::string& message() const { return message_; }
  double time() const { return time_; }
  int reach() const { return reach_; }
  int cell() const { return cell_; }

 private:
  explicit Status(std::string message) : ok_(false), message_(std::move(message)) {}
  bool ok_ = true;
  std::string message_;
  double time_ = 0.0;
  int reach_ = -1;
  int cell_ = -1;
};

}  // namespace canalsim::solver
