#include "core/status.hpp"

#include "core/format.hpp"

namespace canalsim {

Validator& Validator::require(bool ok, const std::string& field, double value, const std::string& expected) {
  if (!ok && status_.is_ok()) status_ = Status::invalid(field, field + " = " + format_g(value) + ": expected " + expected);
  return *this;
}

Validator& Validator::require(bool ok, const std::string& field, const std::string& message) {
  if (!ok && status_.is_ok()) status_ = Status::invalid(field, field + ": " + message);
  return *this;
}

Validator& Validator::nested(const std::string& parent, const Status& inner) {
  if (!inner.is_ok() && status_.is_ok()) status_ = inner.within(parent);
  return *this;
}

}  // namespace canalsim
