// Refusals in the tests: the Options convention (core/status.hpp), options with one field set
// wrongly refused by validate() in one line that names the field, and bad input refused with an
// InputError (core/errors.hpp) that names what is wrong.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "core/errors.hpp"

namespace canalsim::testing {

// Default Options with `edit` applied: whether validate() refuses them with a message that
// contains `expected`.
template <class Options, class Edit>
::testing::AssertionResult refuses(Edit edit, const std::string& expected) {
  Options options;
  edit(options);
  const auto status = options.validate();
  if (status) return ::testing::AssertionFailure() << "accepted; expected a refusal naming '" << expected << "'";
  if (status.message().find(expected) == std::string::npos) {
    return ::testing::AssertionFailure() << "the refusal does not name '" << expected << "': " << status.message();
  }
  return ::testing::AssertionSuccess();
}

// The one line with which validate() refuses default Options with `edit` applied ("" when it
// accepts them), for tests that hold the whole message.
template <class Options, class Edit>
std::string validation_message(Edit edit) {
  Options options;
  edit(options);
  return options.validate().message();
}

// The message of the InputError that `call` throws; `none` when it throws none.
template <class Call>
std::string input_error_of(Call&& call, const std::string& none = "") {
  try {
    call();
  } catch (const InputError& e) {
    return e.what();
  }
  return none;
}

// Whether `call` throws an InputError whose message contains `expected`.
template <class Call>
::testing::AssertionResult refuses_input(Call&& call, const std::string& expected) {
  const std::string error = input_error_of(call);
  if (error.empty()) return ::testing::AssertionFailure() << "accepted; expected an error naming '" << expected << "'";
  if (error.find(expected) == std::string::npos) {
    return ::testing::AssertionFailure() << "the error does not name '" << expected << "': " << error;
  }
  return ::testing::AssertionSuccess();
}

}  // namespace canalsim::testing
