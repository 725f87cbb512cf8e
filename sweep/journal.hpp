// The journal of a running sweep, DIR/table.partial.csv: a first line naming the sweep file by a
// fingerprint of its text, the table's header, then the row of each case as it finishes, in the
// order cases finish, flushed row by row. A sweep that was stopped (a crash, a killed job, a
// machine that went down) resumes from it: the cases it holds are not run again, and the table
// the resumed sweep writes is the one an uninterrupted run writes, byte for byte.
#pragma once

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {

// FNV-1a (64 bits) of the sweep file's text, in hex: the same text, the same sweep.
std::string fingerprint(const std::string& text);

class Journal {
 public:
  // A new journal with its two header lines. Throws InputError, before writing anything, when
  // `file` exists: the journal of an unfinished sweep, to resume or remove.
  static Journal start(const std::filesystem::path& file, const SweepFile& sweep);
  // The journal at `file` opened to go on with, its finished rows read (a last row cut short by
  // the stop is dropped); a new one when there is none. Throws InputError in one line naming the
  // file when it is the journal of another sweep file, or a row is not one of this sweep's.
  static Journal resume(const std::filesystem::path& file, const SweepFile& sweep);

  // The rows read when resuming, by case.
  const std::map<std::size_t, std::string>& finished() const { return finished_; }
  // Appends a finished case's row and flushes it to the file.
  void append(const std::string& row);

 private:
  Journal(std::filesystem::path file, std::map<std::size_t, std::string> finished);

  std::filesystem::path file_;
  std::map<std::size_t, std::string> finished_;
  std::ofstream out_;
};

}  // namespace canalsim::sweep
