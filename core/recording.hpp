// Recording: the uniformly sampled experiment record that simulations write and reduced models,
// calibration and diagnosis read (format in docs/recording-format.md).
//
// A recording file is CSV: optional leading "# key: value" metadata lines, one header line, then
// uniformly sampled rows. Units are the paper's: seconds and millimetres, named in the column
// (t_s, u_mm, y_dwe_mm, q_lps). Only t_s, u_mm and y_dwe_mm are required. The text column
// `regime` ("free"/"submerged") is stored numerically as RegimeCode.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/files.hpp"

namespace canalsim {

// Numeric codes of the `regime` column.
enum class RegimeCode : int { free = 0, submerged = 1 };

struct Recording {
  std::vector<std::pair<std::string, std::string>> metadata;  // "# key: value" lines, in order
  std::vector<std::string> names;                             // column names, header order
  std::vector<std::vector<double>> columns;                   // columns[c][row]
  std::string source;                                         // file it came from, for messages
  std::vector<std::size_t> row_lines;  // line of each row in `source` (empty when not read from text)

  std::size_t size() const { return columns.empty() ? 0 : columns.front().size(); }
  bool has(const std::string& name) const;
  // The column called `name`; throws InputError naming the source when it is absent.
  const std::vector<double>& column(const std::string& name) const;
  std::vector<double>& column(const std::string& name);
  // Adds a column (or replaces one of the same name); its length must equal size() unless empty.
  void set_column(const std::string& name, std::vector<double> values);
  // Metadata value, or `fallback` if absent.
  std::string meta(const std::string& key, const std::string& fallback = "") const;
  void set_meta(const std::string& key, const std::string& value);
  // Sampling period t[1] - t[0] in seconds (requires at least two rows).
  double sample_period() const;
  // "SOURCE:LINE" of a row for messages ("SOURCE, row N" when the line is unknown).
  std::string where(std::size_t row) const;
};

// Column names of the standard format.
namespace columns {
inline constexpr const char* time = "t_s";
inline constexpr const char* gate_command = "u_mm";
inline constexpr const char* gate_position = "x_up_mm";
inline constexpr const char* upstream_level = "y_up_mm";
inline constexpr const char* level_below_gate = "y_dw_mm";
inline constexpr const char* level_downstream_end = "y_dwe_mm";
inline constexpr const char* discharge = "q_lps";
inline constexpr const char* regime = "regime";
}  // namespace columns

struct RecordingReadOptions {
  std::vector<std::string> required = {columns::time, columns::gate_command,
                                       columns::level_downstream_end};
  // Relative tolerance on the spacing of t_s (rounded printing makes it slightly uneven).
  double uniform_tolerance = 0.01;
  // A file's own names for canalsim's columns, canalsim's name → the file's ("y_dwe_mm" →
  // "level"): the header is read with canalsim's names before the required columns are checked.
  std::map<std::string, std::string> column_names;
};

// What a gate-command series (an experiment's `input.file`) needs: time and u_mm only.
inline RecordingReadOptions input_series_columns() {
  RecordingReadOptions options;
  options.required = {columns::time, columns::gate_command};
  return options;
}

// The largest magnitude a recorded number may have (s, mm, L/s): 1e12 mm is a million km. Larger
// values are corrupt data whose squares and sums overflow to inf and NaN further on.
inline constexpr double kMaxRecordedMagnitude = 1.0e12;
// The shortest sampling period read (1 µs): canal sensors sample in tenths of seconds, and the
// models' delays and memories counted in samples would need 10¹² of them at a 1e-12 s step.
inline constexpr double kMinSamplePeriod = 1.0e-6;

// Reads and validates a recording. Throws InputError ("FILE:LINE: problem") on an unreadable
// file, a missing header or required column, a non-numeric, non-finite or out-of-range (above
// kMaxRecordedMagnitude) value, a row of the wrong length, or time that is not increasing and
// uniformly sampled.
Recording read_recording(const std::filesystem::path& file, const RecordingReadOptions& options = {});
Recording parse_recording(const std::string& text, const std::string& source,
                          const RecordingReadOptions& options = {});

// Serialises a recording (metadata, header, rows; `regime` as free/submerged).
std::string format_recording(const Recording& recording);
// Writes atomically: a temporary file beside `file`, renamed over it when complete.
void write_recording(const std::filesystem::path& file, const Recording& recording);

}  // namespace canalsim
