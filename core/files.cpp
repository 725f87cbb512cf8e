#include "core/files.hpp"

#include <fstream>
#include <sstream>
#include <system_error>
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
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open the " + what + " for reading (permission denied?)");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  // A file stream reports a read error as an early end of file: compare with the size the file
  // system gives, so that an I/O error does not pass for a short or empty file.
  const auto size = std::filesystem::is_regular_file(status) ? std::filesystem::file_size(file, ec) : 0;
  if (in.bad() || (!ec && buffer.str().size() < size)) {
    throw InputError(file.string() + ": read error (I/O failure) on the " + what);
  }
  return buffer.str();
}

void write_file_atomically(const std::filesystem::path& file, const std::string& contents) {
  const std::filesystem::path temporary =
      file.string() + ".tmp." + std::to_string(static_cast<long>(::getpid()));
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(file.string() + ": cannot write (directory missing or read-only?)");
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw InputError(file.string() + ": write failed (disk full?)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, file, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw InputError(file.string() + ": cannot replace the file: " + ec.message());
  }
}

}  // namespace canalsim
