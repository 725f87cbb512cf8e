#include "sweep/journal.hpp"

#include <cstdint>
#include <cstdio>
#include <sstream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "sweep/cases.hpp"
#include "sweep/table.hpp"

namespace canalsim::sweep {
namespace {

const std::string kFingerprintLabel = "fingerprint ";

std::string first_line(const SweepFile& sweep) {
  return "# canalsim sweep journal of " + sweep.source + ", " + kFingerprintLabel + fingerprint(sweep.text) + "\n";
}

// The fingerprint a journal's first line names, or "" when the line is not a journal's.
std::string fingerprint_named(const std::string& line) {
  const auto at = line.rfind(kFingerprintLabel);
  if (line.rfind("# canalsim sweep journal", 0) != 0 || at == std::string::npos) return "";
  return line.substr(at + kFingerprintLabel.size());
}

// The case a journal row belongs to; InputError naming the line when the row is not one this
// sweep writes (its leading cells are the case's own: index, point, experiment, values).
std::size_t case_of_row(const std::string& row, const SweepFile& sweep, const std::string& where) {
  const std::vector<std::string> cells = split_csv_line(row);
  const std::string expected = ": expected a row of this sweep's table (remove the journal to start the sweep again)";
  const std::size_t columns = table_columns(sweep).size();
  if (cells.size() != columns) {
    throw InputError(where + ": " + std::to_string(cells.size()) + " cells, not " + std::to_string(columns) + expected);
  }
  std::size_t index = 0;
  try {
    std::size_t used = 0;
    index = std::stoul(cells.front(), &used);
    if (used != cells.front().size()) throw std::invalid_argument("trailing text");
  } catch (const std::exception&) {
    throw InputError(where + ": case '" + cells.front() + "' is not a case number" + expected);
  }
  if (index >= case_count(sweep)) throw InputError(where + ": case " + cells.front() + " past the sweep's last" + expected);
  const std::vector<std::string> own = case_cells(sweep, case_at(sweep, index));
  for (std::size_t k = 0; k < own.size(); ++k) {
    if (cells[k] != own[k]) {
      throw InputError(where + ": case " + cells.front() + " has " + table_columns(sweep)[k] + " " + cells[k] +
                       ", the sweep's is " + own[k] + expected);
    }
  }
  return index;
}

}  // namespace

std::string fingerprint(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return hex;
}

Journal::Journal(std::filesystem::path file, std::map<std::size_t, std::string> finished)
    : file_(std::move(file)), finished_(std::move(finished)), out_(file_, std::ios::app | std::ios::binary) {
  if (!out_) throw InputError(file_.string() + ": cannot open the sweep's journal for writing");
}

Journal Journal::start(const std::filesystem::path& file, const SweepFile& sweep) {
  std::error_code ec;
  if (std::filesystem::exists(file, ec)) {
    throw InputError(file.string() + ": the journal of an unfinished sweep: expected --resume to complete it, "
                     "or the file removed to start again");
  }
  write_file_atomically(file, first_line(sweep) + table_header(sweep));
  return Journal(file, {});
}

Journal Journal::resume(const std::filesystem::path& file, const SweepFile& sweep) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return start(file, sweep);
  const std::string text = read_text_file(file, "sweep journal");
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  const std::string named = fingerprint_named(line);
  if (named.empty()) {
    throw InputError(file.string() + ":1: not a sweep journal: expected the journal canalsim sweep writes, or the "
                     "file removed to start again");
  }
  if (named != fingerprint(sweep.text)) {
    throw InputError(file.string() + ":1: the journal of another sweep file (fingerprint " + named + ", " + sweep.source +
                     "'s is " + fingerprint(sweep.text) + "): expected the sweep file it was started with, or the "
                     "journal removed to start again");
  }
  std::string header;
  if (!std::getline(in, header) || header + "\n" != table_header(sweep)) {
    throw InputError(file.string() + ":2: the journal's columns are not this sweep's: expected the header " +
                     table_header(sweep).substr(0, table_header(sweep).size() - 1) + " (remove the journal to start again)");
  }
  std::map<std::size_t, std::string> finished;
  std::size_t number = 2;
  std::string kept = first_line(sweep) + table_header(sweep);
  for (std::string row; std::getline(in, row);) {
    ++number;
    // A last row without its line break was being written when the sweep stopped: that case runs again.
    if (in.eof()) break;
    const std::size_t index = case_of_row(row, sweep, file.string() + ":" + std::to_string(number));
    if (!finished.emplace(index, row + "\n").second) {
      throw InputError(file.string() + ":" + std::to_string(number) + ": case " + std::to_string(index) +
                       " a second time: expected each case once (remove the journal to start again)");
    }
    kept += row + "\n";
  }
  if (kept != text) write_file_atomically(file, kept);
  return Journal(file, std::move(finished));
}

void Journal::append(const std::string& row) {
  out_ << row << std::flush;
  if (!out_) throw InputError(file_.string() + ": cannot write to the sweep's journal");
}

}  // namespace canalsim::sweep
