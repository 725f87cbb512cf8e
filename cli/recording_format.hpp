// How a command reads a user's own recordings (docs/recording-format.md, "Your own files"): the
// file's column names mapped onto canalsim's and the units of a file whose metadata declare none,
// the same two flags on every command that reads recordings.
//
//   canalsim fit -m lfom field.csv --columns t=time,u=gate,y_dwe=level --units u=m,y=m
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "core/recording.hpp"

namespace canalsim::cli {

struct RecordingFormat {
  std::string columns;  // "t=time,u=gate,y_dwe=level": canalsim's column (short or full name) = the file's
  std::string units;    // "u=m,y=cm": the command's and the levels' unit, one of mm, cm, m

  // Adds --columns and --units to a subcommand.
  void add_options(CLI::App* command);
  // Reads one recording through them, with `options` for everything else. Throws InputError
  // naming the flag (a malformed value), or the file and line (a mapped column the header lacks, a
  // unit the file declares otherwise).
  Recording read(const std::string& file, RecordingReadOptions options = {}) const;
};

}  // namespace canalsim::cli
