// libFuzzer target: fuzz/harness.hpp, fitting_input.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/harness.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  canalsim::fuzz::fitting_input(std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
