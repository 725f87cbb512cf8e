// Small text helpers of the file readers.
#pragma once

#include <string>

namespace canalsim {

// `s` without leading and trailing blanks (spaces, tabs, carriage returns and newlines).
inline std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

}  // namespace canalsim
