// A sweep file (docs/sweep.md): a base scenario, the scenario keys to vary and how, the
// experiments to run at every point, and what to compute for each case.
//
//   scenario = "lab"
//   experiments = ["op1"]
//   [[vary]]
//   key = "pools[1].length_m"
//   values = [4.0, 5.0]
//   [compute]
//   fit = ["LFOM"]
//
// Reading one validates all of it before any case runs: every key and value of the file, the
// experiments against the scenario, and the scenario keys by applying them to the base scenario
// and parsing the result. Every problem is one InputError "FILE:LINE: key: expected ...".
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "reduced_models/models.hpp"

namespace canalsim::sweep {

enum class DistributionKind { uniform, normal, lognormal };

// A distribution a key is drawn from: uniform on [first, second) (low, high), normal (mean, std)
// or lognormal (median, sigma: the standard deviation of its logarithm).
struct Distribution {
  DistributionKind kind = DistributionKind::uniform;
  double first = 0.0;
  double second = 0.0;
};

// One [[vary]] entry: a scenario key and the values it takes, a grid or a distribution.
struct Variation {
  // A scenario key as calibration::edit_scenario_toml names it ("pools[1].manning_n"), or
  // "experiment.KEY": KEY of the experiment each case runs ("experiment.operating_opening_mm").
  std::string key;
  int line = 0;                // of `key = ...` in the sweep file, for messages
  std::vector<double> grid;    // the values of a grid key; empty for a distribution
  std::vector<int> grid_lines; // the line of each: its element of `values`, or `from` and `to`
  std::optional<Distribution> distribution;
  bool logarithmic = false;    // a log-spaced range or a lognormal: plotted on a log axis

  bool is_grid() const { return !distribution; }
};

// What is computed for each case ([compute]).
struct Computations {
  bool summary = true;                     // mean/std/min/max of y_dwe_mm, mean q_lps, share submerged
  std::vector<reduced::ModelKind> fit;     // reduced models fitted to the case's recording
  bool linearize = false;                  // static gain, delay and PRBS-band λ of the linearised pool
  bool diagnose = false;                   // the recording diagnosed against the base scenario
};

struct SweepFile {
  std::string source;            // the file's path as given, for messages
  std::string text;              // the file's text, copied into the output directory
  std::string scenario;          // as written: a built-in name or a path relative to the file
  std::string scenario_source;   // where the base scenario's text came from ("builtin:lab", a path)
  std::string scenario_text;     // the base scenario's TOML
  std::vector<std::string> experiments;
  std::vector<int> experiment_entries;  // each experiment's 1-based [[experiments]] entry in the scenario
  std::vector<Variation> vary;   // in the file's order
  std::optional<std::uint64_t> seed;  // required when any key has a distribution
  int draws = 1;                 // Monte-Carlo cases per grid point (only with distributions)
  std::optional<double> duration_s;   // replaces the experiments' duration_s when given
  Computations compute;
};

// Parses and validates a sweep file's text; `folder` is where a scenario path is taken from.
SweepFile parse_sweep_file(const std::string& text, const std::string& source, const std::filesystem::path& folder);
SweepFile read_sweep_file(const std::filesystem::path& file);

}  // namespace canalsim::sweep
