// Reading and writing whole files the way every command does: a read error is never mistaken for
// a short file, and a write never leaves a partial file or destroys an existing one — not even
// when the process is interrupted (SIGINT, SIGTERM, SIGHUP) in the middle of it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace canalsim {

// The largest text file read: 512 MB (a 10⁶-row recording is ~120 MB).
inline constexpr std::size_t kMaxTextFileBytes = std::size_t{512} << 20;

// The whole text of `file`. Throws InputError naming the file and `what` it is ("scenario file",
// "recording") when it is missing, a directory, larger than kMaxTextFileBytes, or fails to read
// (an I/O error is not an empty file).
std::string read_text_file(const std::filesystem::path& file, const std::string& what);

// Why `file` cannot be replaced by a write, or "" when it can: it does not exist, or it is (or a
// symbolic link leads to) a regular file. A directory, device, FIFO or socket is never replaced.
std::string replaceable_file_problem(const std::filesystem::path& file);

// Writes `contents` to `file` through a temporary file and rename, so a failure never leaves a
// partial file and never destroys an existing one. Throws InputError naming the file.
void write_file_atomically(const std::filesystem::path& file, const std::string& contents);

// Writes a set of files all or nothing: every file goes to a temporary file first; only when all
// are complete are they renamed into place, each existing file kept as a backup until the whole
// set is in. When any step fails, the files already replaced get their previous contents back,
// new ones are removed, and InputError names the file that failed. A symbolic link is written
// through (its target replaced, the link kept); a replaced file keeps its permissions. Throws
// InputError before writing anything when a path is not replaceable (replaceable_file_problem)
// or two paths name the same file.
using FileContents = std::pair<std::filesystem::path, std::string>;
void write_files_atomically(const std::vector<FileContents>& files);

// A path the process must not leave behind: on SIGINT, SIGTERM or SIGHUP a handler (installed with the
// first guard) removes it — or, for a backup, renames it back over `restore_to` — and then lets
// the signal take its usual course. The destructor forgets the path without touching the file
// (release() does the same earlier); cleanup() acts as the handler would. At most 64 live guards.
class InterruptGuard {
 public:
  explicit InterruptGuard(const std::filesystem::path& path, const std::filesystem::path& restore_to = {});
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  ~InterruptGuard() { release(); }

  void release();
  // Removes the path (or restores the backup) now, and forgets it.
  void cleanup();

 private:
  int slot_ = -1;
};

}  // namespace canalsim
