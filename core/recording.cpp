#include "core/recording.hpp"

#include "core/text.hpp"

#include "core/format.hpp"
#include "core/metadata.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <system_error>

namespace canalsim {
namespace {

// A metadata line ends at the first line break: any inside a value (a scenario name with a newline)
// would start a line the reader takes for the header, so they are written as spaces — and read as
// spaces (a carriage return inside a line), so that a recording reads back as it was written.
std::string one_metadata_line(std::string text) {
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

// The comma-separated fields of a line, trimmed; a trailing comma ends with an empty field.
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t begin = 0;
  while (begin < line.size()) {
    const std::size_t comma = std::min(line.find(',', begin), line.size());
    fields.push_back(trim(line.substr(begin, comma - begin)));
    begin = comma + 1;
  }
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

[[noreturn]] void fail(const std::string& source, std::size_t line, const std::string& what) {
  throw InputError(source + ":" + std::to_string(line) + ": " + what);
}

// The header read with canalsim's names where the file has its own (RecordingReadOptions::
// column_names): each named column must be in the header, and canalsim's name must not be there
// as well (which of the two to read would be a guess).
void rename_columns(Recording& rec, const std::map<std::string, std::string>& column_names, const std::string& source,
                    std::size_t line) {
  std::string header;  // as the file wrote it
  for (const auto& name : rec.names) header += (header.empty() ? "" : ", ") + name;
  for (const auto& [ours, theirs] : column_names) {
    const auto at = std::find(rec.names.begin(), rec.names.end(), theirs);
    if (at == rec.names.end()) {
      fail(source, line, "no column " + format_excerpt(theirs) + " to read as " + ours + " (the header has " +
                             format_excerpt(header) + ")");
    }
    if (ours != theirs && rec.has(ours)) {
      fail(source, line, "column " + format_excerpt(theirs) + " is to be read as " + ours + ", but the header has " + ours +
                             " too: expected one of them");
    }
    *at = ours;
  }
}

// True when `text` is a whole number in C syntax ("12", "-0.5", "1e3"): a header of numbers is a
// data row without a header.
bool is_number(const std::string& text) {
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return !text.empty() && ec == std::errc() && ptr == text.data() + text.size();
}

double parse_cell(const std::string& text, const std::string& column, const std::string& source,
                  std::size_t line) {
  if (column == columns::regime) {
    if (text == "free") return static_cast<double>(RegimeCode::free);
    if (text == "submerged") return static_cast<double>(RegimeCode::submerged);
    // Also accepted: the numeric codes 0 (free) and 1 (submerged).
    if (text != "0" && text != "1") {
      fail(source, line, "column regime: expected free, submerged, 0 or 1, found '" + format_excerpt(text) + "'");
    }
  }
  double value = 0.0;
  const char* begin = text.data();
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end || text.empty()) {
    fail(source, line, "column " + format_excerpt(column) + ": expected a number, found '" + format_excerpt(text) + "'");
  }
  if (!std::isfinite(value)) {
    fail(source, line, "column " + column + ": value is " + text + ", expected a finite number");
  }
  if (std::abs(value) > kMaxRecordedMagnitude) {
    fail(source, line, "column " + column + ": value " + format_g(value) + " is out of range: expected a magnitude of at most " +
                           format_g(kMaxRecordedMagnitude));
  }
  return value;
}

void check_time_axis(const Recording& rec, const std::vector<std::size_t>& row_lines,
                     double tolerance) {
  const auto& t = rec.column(columns::time);
  if (t.size() < 2) fail(rec.source, row_lines.empty() ? 1 : row_lines.back(),
                         "expected at least two samples, found " + std::to_string(t.size()));
  const double dt = t[1] - t[0];
  if (dt > 0.0 && dt < kMinSamplePeriod) {
    fail(rec.source, row_lines[1], "t_s steps by " + format_g(dt) + " s: expected a sampling period of at least " +
                                       format_g(kMinSamplePeriod) + " s");
  }
  for (std::size_t i = 1; i < t.size(); ++i) {
    const double step = t[i] - t[i - 1];
    if (!(step > 0.0)) {
      fail(rec.source, row_lines[i], "t_s is not increasing (" + format_g(t[i - 1], 10) +
                                         " then " + format_g(t[i], 10) + ")");
    }
    if (std::abs(step - dt) > tolerance * dt) {
      const double mean_step = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
      fail(rec.source, row_lines[i],
           "t_s is not uniformly sampled (step " + format_g(step, 10) + " s, expected " +
               format_g(dt, 10) + " s, within " + format_g(100.0 * tolerance, 10) +
               " %); resample it first, e.g. canalsim resample " + rec.source + " -o uniform.csv --period " +
               format_g(mean_step, 3));
    }
  }
}

}  // namespace

bool Recording::has(const std::string& name) const {
  return std::find(names.begin(), names.end(), name) != names.end();
}

const std::vector<double>& Recording::column(const std::string& name) const {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    throw InputError((source.empty() ? std::string("recording") : source) +
                     ": missing column " + name);
  }
  return columns[static_cast<std::size_t>(it - names.begin())];
}

std::vector<double>& Recording::column(const std::string& name) {
  return const_cast<std::vector<double>&>(std::as_const(*this).column(name));
}

void Recording::set_column(const std::string& name, std::vector<double> values) {
  if (!columns.empty() && !has(name) && values.size() != size()) {
    throw std::invalid_argument("Recording::set_column: column " + name + " has " +
                                std::to_string(values.size()) + " rows, expected " +
                                std::to_string(size()));
  }
  const auto it = std::find(names.begin(), names.end(), name);
  if (it != names.end()) {
    columns[static_cast<std::size_t>(it - names.begin())] = std::move(values);
    return;
  }
  names.push_back(name);
  columns.push_back(std::move(values));
}

std::string Recording::meta(const std::string& key, const std::string& fallback) const {
  for (const auto& [k, v] : metadata) {
    if (k == key) return v;
  }
  return fallback;
}

void Recording::set_meta(const std::string& key, const std::string& value) {
  for (auto& [k, v] : metadata) {
    if (k == key) {
      v = value;
      return;
    }
  }
  metadata.emplace_back(key, value);
}

double Recording::sample_period() const {
  const auto& t = column(columns::time);
  if (t.size() < 2) throw InputError(source + ": fewer than two samples");
  return t[1] - t[0];
}

std::string Recording::where(std::size_t row) const {
  const std::string name = source.empty() ? std::string("recording") : source;
  if (row < row_lines.size()) return name + ":" + std::to_string(row_lines[row]);
  return name + ", row " + std::to_string(row + 1);
}

Recording parse_recording(const std::string& text, const std::string& source,
                          const RecordingReadOptions& options) {
  Recording rec;
  rec.source = source;
  std::istringstream in(text);
  std::string line;
  std::size_t line_number = 0;
  bool have_header = false;
  std::vector<std::size_t> row_lines, metadata_lines;
  while (std::getline(in, line)) {
    ++line_number;
    // A UTF-8 byte order mark (spreadsheets write one) is not part of the first line's text.
    if (line_number == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    const std::string content = trim(line);
    if (content.empty()) continue;
    if (content.front() == '#') {
      if (have_header) continue;  // comments after the header are ignored
      const std::string body = trim(content.substr(1));
      const auto colon = body.find(':');
      if (colon != std::string::npos) {
        rec.metadata.emplace_back(one_metadata_line(trim(body.substr(0, colon))),
                                  one_metadata_line(trim(body.substr(colon + 1))));
        metadata_lines.push_back(line_number);
      }
      continue;
    }
    const auto fields = split_csv_line(content);
    if (!have_header) {
      if (std::all_of(fields.begin(), fields.end(), is_number)) {
        fail(source, line_number, "the first line is numbers, not a header (expected column names, e.g. t_s,u_mm,y_dwe_mm)");
      }
      for (const auto& name : fields) {
        if (name.empty()) fail(source, line_number, "empty column name in the header");
        if (rec.has(name)) fail(source, line_number, "column " + format_excerpt(name) + " appears twice");
        rec.names.push_back(name);
      }
      rename_columns(rec, options.column_names, source, line_number);
      rec.columns.resize(rec.names.size());
      have_header = true;
      for (const auto& required : options.required) {
        if (!rec.has(required)) {
          fail(source, line_number, "missing required column " + required + " (header has " +
                                        std::to_string(rec.names.size()) + " columns)");
        }
      }
      continue;
    }
    if (fields.size() != rec.names.size()) {
      fail(source, line_number, "expected " + std::to_string(rec.names.size()) +
                                    " fields, found " + std::to_string(fields.size()));
    }
    for (std::size_t c = 0; c < fields.size(); ++c) {
      rec.columns[c].push_back(parse_cell(fields[c], rec.names[c], source, line_number));
    }
    row_lines.push_back(line_number);
  }
  if (!have_header) {
    throw InputError(source + ": " + (line_number == 0 ? "the file is empty" : "only comments and blank lines") +
                     ", no header line (expected column names, e.g. t_s,u_mm,y_dwe_mm)");
  }
  if (rec.has(columns::time)) check_time_axis(rec, row_lines, options.uniform_tolerance);
  check_metadata(rec, std::isfinite(options.uniform_tolerance),
                 [&](std::size_t i) { return source + ":" + std::to_string(metadata_lines[i]); });
  rec.row_lines = std::move(row_lines);
  return rec;
}

Recording read_recording(const std::filesystem::path& file, const RecordingReadOptions& options) {
  return parse_recording(read_text_file(file, "recording"), file.string(), options);
}


std::string format_recording(const Recording& rec) {
  std::string out;
  for (const auto& [key, value] : rec.metadata) {
    out += "# " + one_metadata_line(key) + ": " + one_metadata_line(value) + "\n";
  }
  for (std::size_t c = 0; c < rec.names.size(); ++c) {
    out += (c ? "," : "") + rec.names[c];
  }
  out += "\n";
  for (std::size_t row = 0; row < rec.size(); ++row) {
    for (std::size_t c = 0; c < rec.names.size(); ++c) {
      if (c) out += ",";
      const double v = rec.columns[c][row];
      if (rec.names[c] == columns::regime) {
        out += v >= 0.5 ? "submerged" : "free";
      } else {
        // Time with 15 digits: at t = 1e8 s, ten would round a 0.13 s step by up to 4 %, more than
        // the reader's uniformity tolerance, and the file would not read back.
        out += format_g(v, rec.names[c] == columns::time ? 15 : 10);
      }
    }
    out += "\n";
  }
  return out;
}

void write_recording(const std::filesystem::path& file, const Recording& recording) {
  write_file_atomically(file, format_recording(recording));
}

}  // namespace canalsim
