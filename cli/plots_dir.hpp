// --plots-dir DIR, shared by the commands whose reports have figures (reproduce, calibrate
// --report, diagnose --report, linearize): every figure also as a standalone DIR/NAME.svg, written
// in one all-or-nothing set with the command's other outputs (core/files.hpp), so a failing or
// interrupted run neither destroys the files DIR already holds nor leaves some of the new ones.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "cli/checks.hpp"
#include "core/files.hpp"
#include "plot/figure.hpp"

namespace canalsim::cli {

struct PlotsDirectory {
  std::string dir;

  // `files` lists the names written, for --help ("RECORDING_levels_and_residual.svg, …").
  void add_option(CLI::App* cmd, const std::string& files) {
    cmd->add_option("--plots-dir", dir,
                    "Also write every plot as a standalone SVG file in DIR (created if missing): " + files);
  }

  // Before the work: DIR can be created or written.
  void check() const {
    if (!dir.empty()) check_creatable_directory("--plots-dir", dir);
  }

  // Writes `outputs` and, with --plots-dir, the figures' files, all or nothing; a DIR this call
  // created is removed again when the set cannot be written. Returns every file written.
  std::vector<FileContents> write(std::vector<FileContents> outputs, const std::vector<plot::Figure>& figures) const {
    namespace fs = std::filesystem;
    std::error_code ec;
    const bool created = !dir.empty() && !fs::exists(dir, ec);
    if (!dir.empty()) {
      for (auto& file : plot::svg_files(dir, figures)) outputs.push_back(std::move(file));
      create_directory_for("--plots-dir", dir);
    }
    try {
      write_files_atomically(outputs);
    } catch (...) {
      if (created) fs::remove(dir, ec);
      throw;
    }
    return outputs;
  }
};

}  // namespace canalsim::cli
