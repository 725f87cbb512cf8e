// Strict reading of a TOML table: every key is checked for type and range, unknown keys are
// errors, and every message names the file, the line and the dotted key with what was expected:
//   lab.toml:12: pools[0].bottom_width_m = -0.08: expected a number in (0, 1000] m
#pragma once

#include <cstdint>
#include <initializer_list>
#include <set>
#include <string>
#include <vector>

#include <toml++/toml.h>

namespace canalsim::scenarios {

// A number as messages print it ("%g": 6 significant digits, more when six would not tell it
// from a neighbouring bound: 1.0000001).
std::string format_value(double v);
// A value echoed in a message: the first 60 characters and the length of a longer one, so that a
// 1 MB field does not make a 1 MB error line.
std::string excerpt(const std::string& text);

// Inclusive or exclusive numeric range used in messages and checks.
struct Range {
  double min;
  double max;
  bool min_open = false;  // true: value must be > min
  bool max_open = false;  // true: value must be < max
  bool contains(double v) const;
  std::string describe() const;  // "(0, 1000]"
};

class TomlTable {
 public:
  TomlTable(const toml::table& table, std::string file, std::string path);

  double number(const std::string& key, double fallback, Range range, const std::string& unit);
  double required_number(const std::string& key, Range range, const std::string& unit);
  int integer(const std::string& key, int fallback, int min, int max);
  std::uint64_t seed(const std::string& key, std::uint64_t fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string string(const std::string& key, const std::string& fallback);
  // A string that must be one of `allowed`.
  std::string choice(const std::string& key, const std::string& fallback,
                     std::initializer_list<const char*> allowed);
  bool has(const std::string& key) const;
  bool is_string(const std::string& key) const;  // present and a string
  TomlTable table(const std::string& key);
  // An array of tables ([[key]]); empty when absent.
  std::vector<TomlTable> tables(const std::string& key);
  std::vector<double> numbers(const std::string& key, Range range, const std::string& unit);

  // Every key of the table, in the file's order (for tables whose keys are names, not a schema).
  std::vector<std::string> keys() const;

  // Throws InputError for every key that was present but never read.
  void reject_unknown_keys() const;

  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  // "file:line: key = value: what" for a value that is valid alone but not in context.
  [[noreturn]] void fail_value(const std::string& key, const std::string& value, const std::string& what) const;
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }

 private:
  const toml::node* find(const std::string& key);
  std::string dotted(const std::string& key) const;
  std::string where(const toml::node* node) const;

  const toml::table& table_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

}  // namespace canalsim::scenarios
