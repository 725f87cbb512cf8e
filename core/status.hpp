// Validation of Options structs, one convention for every module (after Ceres'
// Solver::Options::IsValid): validate() returns a Status that is ok, or names the first field
// that is wrong and what was expected, in one line: "max_lag = 0: expected 1..1000".
#pragma once

#include <string>
#include <utility>

namespace canalsim {

class [[nodiscard]] Status {
 public:
  Status() = default;  // ok
  static Status ok() { return {}; }
  // `field` is wrong; `message` is the whole line and starts with the field's name.
  static Status invalid(std::string field, std::string message) {
    Status s;
    s.ok_ = false;
    s.field_ = std::move(field);
    s.message_ = std::move(message);
    return s;
  }

  bool is_ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const std::string& field() const { return field_; }    // empty when ok
  const std::string& message() const { return message_; }  // empty when ok

  // The same failure seen from an enclosing struct: field "max_lag" becomes "tests.max_lag".
  Status within(const std::string& parent) const {
    return ok_ ? *this : invalid(parent + "." + field_, parent + "." + message_);
  }

 private:
  bool ok_ = true;
  std::string field_;
  std::string message_;
};

// Checks in order; the first failure is kept.
//   return Validator()
//       .require(max_lag >= 1 && max_lag <= 1000, "max_lag", max_lag, "1..1000")
//       .require(!name.empty(), "name", "expected a name")
//       .status();
// Write conditions so that NaN fails them (x > 0, not !(x <= 0)).
class Validator {
 public:
  // "field = value: expected EXPECTED" unless `ok`.
  Validator& require(bool ok, const std::string& field, double value, const std::string& expected);
  // "field: MESSAGE" unless `ok`.
  Validator& require(bool ok, const std::string& field, const std::string& message);
  // A nested struct's status, its field prefixed with `parent`.
  Validator& nested(const std::string& parent, const Status& inner);
  bool failed() const { return !status_.is_ok(); }
  Status status() const { return status_; }

 private:
  Status status_;
};

}  // namespace canalsim
