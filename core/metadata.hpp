// The metadata keys canalsim reads or writes in a recording's "# key: value" lines, each with the
// range its value must lie in (docs/recording-format.md, "Metadata keys"). The reader checks every
// known key where the file is read, so that a malformed value ("operating_opening_mm: fifteen",
// "initial_y_up_mm: nan") is an error naming the file, line and key — never a value silently
// ignored that changes a result. Keys it does not know are kept as text.
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "core/recording.hpp"

namespace canalsim {

struct MetadataKey {
  enum class Type { text, number, integer };
  std::string_view name;
  Type type = Type::text;
  double low = 0.0, high = 0.0;  // a number's or integer's range, both ends included ...
  bool above_low = false;        // ... except `low` when this is set (> low)
  std::string_view unit;         // "mm", "s", "m³", "" for a plain number
  std::string_view meaning;      // one line, as docs/recording-format.md says it
};

// Every key canalsim knows, in the order docs/recording-format.md lists them.
std::span<const MetadataKey> known_metadata_keys();

// The range of a key as docs/recording-format.md writes it: "[0, 100000]", "(0, 3600]", "text".
std::string metadata_range_text(const MetadataKey& key);

// The key called `name`, or nullptr for a key canalsim does not know.
const MetadataKey* find_metadata_key(std::string_view name);

// "" when `value` is valid for the known key `key` (any value is valid for an unknown key), else
// what was expected: "'fifteen': expected a number of mm in [0, 1e+05]".
std::string metadata_value_problem(std::string_view key, const std::string& value);

// The number under the known numeric key `key`, or nullopt when the recording has none. Throws
// InputError naming the recording and the key when the value is malformed (a recording built in
// memory is checked here; one read from a file was already checked by the reader).
std::optional<double> metadata_number(const Recording& recording, std::string_view key);

// Checks a recording's metadata as a whole: every known key's value, no key twice, and no two
// keys that contradict each other or the rows (a unit of mm with a scale other than 1, a
// sampling_period_s other than the t_s step). `where(i)` names the i-th metadata line
// ("FILE:LINE"); the InputError thrown starts with it.
void check_metadata(const Recording& recording, bool uniform_time,
                    const std::function<std::string(std::size_t)>& where);

}  // namespace canalsim
