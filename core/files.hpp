// Reading and writing whole files the way every command does: a read error is never mistaken for
// a short file, and a write never leaves a partial file or destroys an existing one.
#pragma once

#include <filesystem>
#include <string>

namespace canalsim {

// The whole text of `file`. Throws InputError naming the file and `what` it is ("scenario file",
// "recording") when it is missing, a directory, or fails to read (an I/O error is not an empty file).
std::string read_text_file(const std::filesystem::path& file, const std::string& what);

// Writes `contents` to `file` through a temporary file and rename, so a failure never leaves a
// partial file and never destroys an existing one. Throws InputError naming the file.
void write_file_atomically(const std::filesystem::path& file, const std::string& contents);

}  // namespace canalsim
