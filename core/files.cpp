#include "core/files.hpp"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <sstream>
#include <system_error>
#include <sys/stat.h>
#include <unistd.h>

#include "core/errors.hpp"

namespace canalsim {

std::string read_text_file(const std::filesystem::path& file, const std::string& what) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (ec || !std::filesystem::exists(status)) {
    throw InputError(file.string() + ": cannot open the " + what + " for reading (no such file)");
  }
  if (std::filesystem::is_directory(status)) {
    throw InputError(file.string() + ": is a directory, expected a " + what);
  }
  // A named FIFO blocks the open until something writes to it, which may be never. (A pipe from
  // the shell, <(command), is a link in /dev/fd to a pipe that has its writer: it is read.)
  const auto own = std::filesystem::symlink_status(file, ec);
  if (std::filesystem::is_fifo(own) || std::filesystem::is_socket(own)) {
    throw InputError(file.string() + ": is a " + (std::filesystem::is_fifo(own) ? "FIFO" : "socket") + ", expected a " +
                     what + " file (to read a stream, give <(command) instead)");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open the " + what + " for reading (permission denied?)");
  // Read in chunks up to a ceiling: a device or pipe without end (/dev/zero given as a recording)
  // must not fill the memory.
  std::ostringstream buffer;
  std::string chunk(1 << 16, '\0');
  std::size_t total = 0;
  while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
    total += static_cast<std::size_t>(in.gcount());
    if (total > kMaxTextFileBytes) {
      throw InputError(file.string() + ": the " + what + " is larger than " +
                       std::to_string(kMaxTextFileBytes >> 20) + " MB: expected a text file");
    }
    buffer.write(chunk.data(), in.gcount());
    if (in.eof()) break;
  }
  // A file stream reports a read error as an early end of file: compare with the size the file
  // system gives, so that an I/O error does not pass for a short or empty file.
  const auto size = std::filesystem::is_regular_file(status) ? std::filesystem::file_size(file, ec) : 0;
  if (in.bad() || (!ec && buffer.str().size() < size)) {
    throw InputError(file.string() + ": read error (I/O failure) on the " + what);
  }
  return buffer.str();
}

// ---- interrupt guards -------------------------------------------------------------------------
//
// The registry is a fixed array of slots so that the signal handler touches nothing but
// lock-free atomics, char arrays and the async-signal-safe calls unlink(2) and rename(2).

namespace {

constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;

struct Slot {
  std::atomic<int> state{0};  // kFree, kFilling, kLive
  char path[kPathBytes] = {};
  char restore_to[kPathBytes] = {};  // empty: remove `path`; else rename `path` over it
};
constexpr int kFree = 0, kFilling = 1, kLive = 2;
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

Slot g_slots[kSlots];
// The signals that end a run with its outputs unwritten: Ctrl-C, kill, and a closed terminal.
constexpr int kGuardedSignals[] = {SIGINT, SIGTERM, SIGHUP};
struct sigaction g_previous[std::size(kGuardedSignals)];

struct sigaction* previous_action(int signal_number) {
  for (std::size_t i = 0; i < std::size(kGuardedSignals); ++i) {
    if (kGuardedSignals[i] == signal_number) return &g_previous[i];
  }
  return nullptr;
}

void undo(Slot& slot) {
  if (slot.restore_to[0] != '\0') {
    ::rename(slot.path, slot.restore_to);
  } else {
    ::unlink(slot.path);
  }
}

extern "C" void remove_live_paths_and_reraise(int signal_number) {
  for (Slot& slot : g_slots) {
    if (slot.state.load() == kLive) undo(slot);
  }
  // The signal's previous disposition (the default: terminate) takes over; it is blocked while
  // this handler runs, so the raised one is delivered as the handler returns.
  ::sigaction(signal_number, previous_action(signal_number), nullptr);
  ::raise(signal_number);
}

void install_handler(int signal_number, struct sigaction* previous) {
  ::sigaction(signal_number, nullptr, previous);
  if (previous->sa_handler == SIG_IGN) return;  // an ignored signal stays ignored (nohup)
  struct sigaction action {};
  action.sa_handler = remove_live_paths_and_reraise;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  ::sigaction(signal_number, &action, nullptr);
}

void copy_path(char (&to)[kPathBytes], const std::filesystem::path& from) {
  const std::string text = from.string();
  if (text.size() >= kPathBytes) throw InputError(text.substr(0, 200) + "...: path too long");
  std::memcpy(to, text.c_str(), text.size() + 1);
}

}  // namespace

InterruptGuard::InterruptGuard(const std::filesystem::path& path, const std::filesystem::path& restore_to) {
  static std::once_flag installed;
  std::call_once(installed, [] {
    for (const int signal_number : kGuardedSignals) install_handler(signal_number, previous_action(signal_number));
  });
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling)) continue;
    try {
      copy_path(g_slots[i].path, path);
      copy_path(g_slots[i].restore_to, restore_to);
    } catch (...) {
      g_slots[i].state.store(kFree);
      throw;
    }
    g_slots[i].state.store(kLive);
    slot_ = i;
    return;
  }
  throw std::logic_error("InterruptGuard: more than 64 files being written at once");
}

void InterruptGuard::release() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree);
  slot_ = -1;
}

void InterruptGuard::cleanup() {
  if (slot_ < 0) return;
  g_slots[slot_].state.store(kFilling);  // the handler leaves it alone while we act
  undo(g_slots[slot_]);
  release();
}

// ---- writing ----------------------------------------------------------------------------------

namespace {

std::filesystem::path beside(const std::filesystem::path& file, const char* kind) {
  return file.string() + "." + kind + "." + std::to_string(static_cast<long>(::getpid()));
}

// Writes the temporary file; it takes the permissions of the file it will replace, if any.
void write_contents(const std::filesystem::path& temporary, const std::filesystem::path& file,
                    const std::string& contents) {
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(file.string() + ": cannot write (directory missing or read-only?)");
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) throw InputError(file.string() + ": write failed (disk full?)");
  }
  struct stat existing {};
  if (::stat(file.c_str(), &existing) == 0 && ::chmod(temporary.c_str(), existing.st_mode & 07777) != 0) {
    throw InputError(file.string() + ": cannot keep the file's permissions: " + std::strerror(errno));
  }
}

// A second name for `file`'s current contents that survives the rename over `file`: a hard link
// (the file never goes missing), or a copy where the file system has no hard links.
void keep_backup(const std::filesystem::path& file, const std::filesystem::path& backup) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) throw InputError(file.string() + ": is a directory, expected a file");
  std::filesystem::remove(backup, ec);
  if (::link(file.c_str(), backup.c_str()) == 0) return;
  if (!std::filesystem::copy_file(file, backup, ec)) {
    std::error_code ignored;
    std::filesystem::remove(backup, ignored);
    throw InputError(file.string() + ": cannot keep the previous file while replacing it: " + ec.message());
  }
}

// `file` and every path its symbolic links lead to, in order (at most 40 links, as the kernel).
// Throws InputError for a longer chain (a loop) or a link that cannot be read.
std::vector<std::filesystem::path> link_chain(const std::filesystem::path& file) {
  namespace fs = std::filesystem;
  std::vector<fs::path> chain{file};
  for (int hops = 0; hops < 40; ++hops) {
    std::error_code ec;
    if (!fs::is_symlink(fs::symlink_status(chain.back(), ec))) return chain;
    const fs::path target = fs::read_symlink(chain.back(), ec);
    if (ec) throw InputError(file.string() + ": cannot read the symbolic link: " + ec.message());
    chain.push_back((target.is_absolute() ? target : chain.back().parent_path() / target).lexically_normal());
  }
  throw InputError(file.string() + ": too many levels of symbolic links");
}

// The file a write to `file` replaces: `file`, or the end of its chain of symbolic links (which
// may not exist yet: a dangling link is written through to its target, or fails there).
std::filesystem::path written_path(const std::filesystem::path& file) { return link_chain(file).back(); }

}  // namespace

std::string replaceable_file_problem(const std::filesystem::path& file) {
  namespace fs = std::filesystem;
  std::error_code ec;
  // The process's own descriptors (/proc/self/fd/1 is whatever stdout is) and the kernel's
  // directories hold no file of the user's: never replaced, whatever they resolve to.
  const std::vector<fs::path> chain = link_chain(file);
  for (std::size_t i = 0; i < chain.size(); ++i) {
    const std::string text = fs::absolute(chain[i], ec).lexically_normal().string();
    for (const std::string system : {"/proc/", "/sys/", "/dev/"}) {
      if (text.rfind(system, 0) == 0) {
        return std::string(i == 0 ? "is in " : "links to " + text + ", in ") + system.substr(0, system.size() - 1) +
               ": expected a regular file (or a new path) to write";
      }
    }
  }
  const fs::file_status status = fs::status(file, ec);  // follows a symbolic link to its target
  if (ec || !fs::exists(status) || fs::is_regular_file(status)) return "";
  const char* kind = fs::is_directory(status)  ? "a directory"
                     : fs::is_fifo(status)     ? "a FIFO"
                     : fs::is_socket(status)   ? "a socket"
                     : fs::is_character_file(status) || fs::is_block_file(status) ? "a device"
                                                                                 : "not a regular file";
  const bool linked = fs::is_symlink(fs::symlink_status(file, ec));
  return std::string(linked ? "links to " : "is ") + kind + ": expected a regular file (or a new path) to write";
}

void write_file_atomically(const std::filesystem::path& file, const std::string& contents) {
  write_files_atomically({{file, contents}});
}

void write_files_atomically(const std::vector<FileContents>& requested) {
  namespace fs = std::filesystem;
  // 0. What will be written: a symbolic link's target (the link stays), only regular files
  //    replaced, no file twice (two names of one file included).
  std::vector<FileContents> files;
  for (const auto& [file, contents] : requested) {
    if (const std::string problem = replaceable_file_problem(file); !problem.empty()) {
      throw InputError(file.string() + ": " + problem);
    }
    files.emplace_back(written_path(file), contents);
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (fs::absolute(files[i].first).lexically_normal() == fs::absolute(files[j].first).lexically_normal()) {
        throw InputError(requested[i].first.string() + ": the same file as " + requested[j].first.string() +
                         ": expected a different file for each output");
      }
    }
  }
  // 1. Every file complete under a temporary name; a failure removes them all (the guards'
  //    cleanup), and nothing that was there has been touched.
  std::vector<std::unique_ptr<InterruptGuard>> temporaries;
  auto remove_temporaries = [&] {
    for (auto& guard : temporaries) guard->cleanup();
  };
  try {
    for (const auto& [file, contents] : files) {
      const fs::path temporary = beside(file, "tmp");
      temporaries.push_back(std::make_unique<InterruptGuard>(temporary));
      write_contents(temporary, file, contents);
    }
  } catch (...) {
    remove_temporaries();
    throw;
  }
  // 2. Renamed into place one by one. Each existing file keeps a backup whose guard renames it
  //    back (a new file's guard removes it) if a later file fails or the process is interrupted.
  std::vector<std::unique_ptr<InterruptGuard>> committed;
  std::vector<fs::path> backups;
  try {
    for (std::size_t i = 0; i < files.size(); ++i) {
      const fs::path& file = files[i].first;
      std::error_code ec;
      const bool existed = fs::exists(fs::symlink_status(file, ec));
      if (existed) {
        // Until the backup is complete an interruption removes it; from then on it is restored.
        const fs::path backup = beside(file, "bak");
        InterruptGuard half_made(backup);
        keep_backup(file, backup);
        committed.push_back(std::make_unique<InterruptGuard>(backup, file));
        half_made.release();
        backups.push_back(backup);
      } else {
        committed.push_back(std::make_unique<InterruptGuard>(file));
      }
      fs::rename(beside(file, "tmp"), file, ec);
      if (ec) {
        // This file was not replaced (an immutable file, say): it needs no restoring, and its
        // backup, if it has one, goes; the files before it are restored below.
        committed.back()->release();
        committed.pop_back();
        if (existed) {
          ::unlink(backups.back().c_str());
          backups.pop_back();
        }
        throw InputError(file.string() + ": cannot replace the file: " + ec.message());
      }
      temporaries[i]->release();
    }
  } catch (...) {
    for (auto it = committed.rbegin(); it != committed.rend(); ++it) (*it)->cleanup();
    remove_temporaries();
    throw;
  }
  // 3. The whole set is in: forget the guards, drop the backups.
  for (auto& guard : committed) guard->release();
  for (const auto& backup : backups) ::unlink(backup.c_str());
}

}  // namespace canalsim
