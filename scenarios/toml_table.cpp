#include "scenarios/toml_table.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <limits>

#include "core/format.hpp"
#include "core/recording.hpp"

namespace canalsim::scenarios {
std::string format_value(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  // Six digits unless they lose the value: cfl = 1.0000001 must not read "= 1" next to "(0, 1]".
  if (std::strtod(buffer, nullptr) == v || !std::isfinite(v)) return buffer;
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;  // shortest round trip
  return std::string(buffer, end);
}

std::string excerpt(const std::string& text) { return format_excerpt(text); }

namespace {

std::string type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::table: return "a table";
    case toml::node_type::array: return "an array";
    default: return "a date/time";
  }
}

}  // namespace

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  const bool above = min_open ? v > min : v >= min;
  const bool below = max_open ? v < max : v <= max;
  return above && below;
}

std::string Range::describe() const {
  // An unbounded side is open whatever the flag says: no finite number reaches infinity.
  std::string text(std::isinf(min) ? "(-∞" : (min_open ? "(" : "["));
  if (!std::isinf(min)) text.append(format_value(min));
  text.append(", ");
  if (!std::isinf(max)) text.append(format_value(max));
  text.append(std::isinf(max) ? "∞)" : (max_open ? ")" : "]"));
  return text;
}

TomlTable::TomlTable(const toml::table& table, std::string file, std::string path)
    : table_(table), file_(std::move(file)), path_(std::move(path)) {}

std::string TomlTable::dotted(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

std::string TomlTable::where(const toml::node* node) const {
  const auto line = node ? node->source().begin.line : table_.source().begin.line;
  return file_ + ":" + std::to_string(line);
}

void TomlTable::fail(const std::string& key, const std::string& what) const {
  const toml::node* node = key.empty() ? nullptr : table_.get(key);
  throw InputError(where(node) + ": " + (key.empty() ? path_ : dotted(key)) + ": " + what);
}

void TomlTable::fail_value(const std::string& key, const std::string& value, const std::string& what) const {
  throw InputError(where(table_.get(key)) + ": " + dotted(key) + " = " + excerpt(value) + ": " + what);
}

bool TomlTable::has(const std::string& key) const { return table_.contains(key); }

bool TomlTable::is_string(const std::string& key) const {
  const toml::node* node = table_.get(key);
  return node && node->is_string();
}

const toml::node* TomlTable::find(const std::string& key) {
  used_.insert(key);
  return table_.get(key);
}

double TomlTable::number(const std::string& key, double fallback, Range range,
                         const std::string& unit) {
  const toml::node* node = find(key);
  if (!node) return fallback;
  const auto value = node->value<double>();
  const std::string expected = "expected a number in " + range.describe() + (unit.empty() ? "" : " " + unit);
  if (!value || !(node->is_integer() || node->is_floating_point())) {
    throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) + ": " + expected);
  }
  if (!range.contains(*value)) {
    throw InputError(where(node) + ": " + dotted(key) + " = " + format_value(*value) + ": " + expected);
  }
  return *value;
}

double TomlTable::required_number(const std::string& key, Range range, const std::string& unit) {
  if (!has(key)) {
    throw InputError(where(nullptr) + ": " + dotted(key) + " is missing: expected a number in " +
                     range.describe() + (unit.empty() ? "" : " " + unit));
  }
  return number(key, 0.0, range, unit);
}

int TomlTable::integer(const std::string& key, int fallback, int min, int max) {
  const toml::node* node = find(key);
  if (!node) return fallback;
  const std::string expected =
      "expected an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  if (!node->is_integer()) {
    throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) + ": " + expected);
  }
  const auto value = *node->value<std::int64_t>();
  if (value < min || value > max) {
    throw InputError(where(node) + ": " + dotted(key) + " = " + std::to_string(value) + ": " + expected);
  }
  return static_cast<int>(value);
}

std::uint64_t TomlTable::seed(const std::string& key, std::uint64_t fallback) {
  const toml::node* node = find(key);
  if (!node) return fallback;
  if (!node->is_integer() || *node->value<std::int64_t>() < 0) {
    throw InputError(where(node) + ": " + dotted(key) + ": expected a non-negative integer seed");
  }
  return static_cast<std::uint64_t>(*node->value<std::int64_t>());
}

bool TomlTable::boolean(const std::string& key, bool fallback) {
  const toml::node* node = find(key);
  if (!node) return fallback;
  if (!node->is_boolean()) {
    throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) +
                     ": expected true or false");
  }
  return *node->value<bool>();
}

std::string TomlTable::string(const std::string& key, const std::string& fallback) {
  const toml::node* node = find(key);
  if (!node) return fallback;
  if (!node->is_string()) {
    throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) + ": expected a string");
  }
  std::string text = *node->value<std::string>();
  // A control character (a NUL above all) would cut a file name or a message short where the text
  // is used; a name ("name", a file) is one line. Tabs and line breaks are kept in descriptions.
  const bool one_line = key == "name" || key == "file";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte == 0x7f || (byte < 0x20 && (one_line || (c != '\n' && c != '\t' && c != '\r')))) {
      throw InputError(where(node) + ": " + dotted(key) + " contains the control character " + std::to_string(byte) +
                       ": expected printable text");
    }
  }
  return text;
}

std::string TomlTable::choice(const std::string& key, const std::string& fallback,
                              std::initializer_list<const char*> allowed) {
  const std::string value = string(key, fallback);
  std::string list;
  for (const char* option : allowed) {
    if (value == option) return value;
    list += (list.empty() ? "" : ", ") + std::string(option);
  }
  throw InputError(where(table_.get(key)) + ": " + dotted(key) + " = \"" + excerpt(value) +
                   "\": expected one of " + list);
}

TomlTable TomlTable::table(const std::string& key) {
  static const toml::table empty;
  const toml::node* node = find(key);
  if (!node) return TomlTable(empty, file_, dotted(key));
  if (!node->is_table()) {
    throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) + ": expected a table");
  }
  return TomlTable(*node->as_table(), file_, dotted(key));
}

std::vector<TomlTable> TomlTable::tables(const std::string& key) {
  std::vector<TomlTable> result;
  const toml::node* node = find(key);
  if (!node) return result;
  const toml::array* array = node->as_array();
  if (!array || !array->is_array_of_tables()) {
    throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) +
                     ": expected an array of tables ([[" + dotted(key) + "]])");
  }
  for (std::size_t i = 0; i < array->size(); ++i) {
    result.emplace_back(*array->get(i)->as_table(), file_, dotted(key) + "[" + std::to_string(i) + "]");
  }
  return result;
}

std::vector<double> TomlTable::numbers(const std::string& key, Range range, const std::string& unit) {
  std::vector<double> result;
  const toml::node* node = find(key);
  if (!node) return result;
  const toml::array* array = node->as_array();
  const std::string expected = "expected an array of numbers in " + range.describe() + " " + unit;
  if (!array) throw InputError(where(node) + ": " + dotted(key) + " is " + type_name(*node) + ": " + expected);
  for (const auto& element : *array) {
    const auto value = element.value<double>();
    if (!value || !range.contains(*value)) {
      throw InputError(where(&element) + ": " + dotted(key) + ": " + expected);
    }
    result.push_back(*value);
  }
  return result;
}

std::vector<std::string> TomlTable::keys() const {
  std::vector<std::string> out;
  for (const auto& [key, node] : table_) out.emplace_back(key.str());
  return out;
}

void TomlTable::reject_unknown_keys() const {
  for (const auto& [key, node] : table_) {
    const std::string name(key.str());
    if (!used_.count(name)) {
      throw InputError(where(&node) + ": unknown key " + excerpt(dotted(name)) +
                       " (docs/scenarios.md lists the keys)");
    }
  }
}

}  // namespace canalsim::scenarios
