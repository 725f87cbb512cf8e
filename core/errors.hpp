// The error every module throws for bad user input. Its message is one line that names the file
// (and line or key) or the flag, and what was expected; the CLI prints it as it is
// ("canalsim: error: MESSAGE", exit status 1).
#pragma once

#include <stdexcept>

namespace canalsim {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace canalsim
