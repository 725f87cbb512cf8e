// Small text helpers of the file readers and the tables.
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

// The characters of UTF-8 text (bytes that do not continue a character): the columns it takes
// in a table, where "±" and "∞" are one column each but two and three bytes.
inline std::size_t text_width(const std::string& s) {
  std::size_t n = 0;
  for (const char c : s) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  return n;
}

}  // namespace canalsim
