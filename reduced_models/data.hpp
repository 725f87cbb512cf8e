// Experiment data for the reduced models: a recording turned into the signals the models use,
// with the operating point the paper's deviations (Δu, Δy_dwe) are taken from.
//
// Levels and gate openings are in millimetres here, as in the paper's tables, so the flow-regime
// conditions (8)/(10) compare millimetres; times are in seconds. A recording may hold its
// command and its levels in other units and declare them in its metadata:
//   # u_unit: counts                 # y_unit: cm
//   # u_scale_mm_per_unit: 0.13      # y_scale_mm_per_unit: 10
// u_mm and x_up_mm are then multiplied by the u scale, y_up_mm, y_dw_mm and y_dwe_mm by the y
// scale; the units are kept so that gains can be reported in them (declared_gain_factor).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/recording.hpp"
#include "core/status.hpp"

namespace canalsim::reduced {

struct DataOptions {
  // Upstream pool level to use when the recording has no y_up_mm column (the paper's lab
  // canal regulated it at 60 mm). Without it, models that need y_up reject such recordings.
  std::optional<double> upstream_level_mm;
  // Operating point. By default u0 = u(0) and y0 = the mean of y_dwe over the samples before
  // u first changes (at most `rest_samples_max` of them): the pool is at rest there.
  std::optional<double> u0_mm;  // default: the recording's operating_opening_mm metadata, else u[0]
  std::optional<double> y0_mm;
  std::size_t rest_samples_max = 50;
  // An input whose range max(u) − min(u) is at most this carries no excitation (rejected).
  double min_excitation_mm = 1e-6;

  [[nodiscard]] Status validate() const;  // ok, or one line naming the field (core/status.hpp)
};

struct ExperimentData {
  std::string source;             // file name, for messages and reports
  double h = 0.0;                 // sampling period, s
  std::vector<double> t_s;        // time, s
  std::vector<double> u_mm;       // gate command u(t), absolute
  std::vector<double> y_dwe_mm;   // recorded downstream-end level, absolute
  std::vector<double> y_up_mm;    // upstream level (column or the constant option); may be empty
  std::vector<double> x_up_mm;    // recorded gate position; empty when absent
  double u0_mm = 0.0;             // operating point of the input
  double y0_mm = 0.0;             // operating point of the output
  bool y_up_is_constant_option = false;
  // Declared units of the recording's command and levels ("mm", scale 1, unless declared).
  std::string u_unit = "mm", y_unit = "mm";
  double u_scale_mm_per_unit = 1.0, y_scale_mm_per_unit = 1.0;

  std::size_t size() const { return u_mm.size(); }
  double duration() const { return h * static_cast<double>(size()); }
  bool has_upstream_level() const { return !y_up_mm.empty(); }
};

// Builds the experiment data from a recording that has already been read and validated
// (read_recording rejects non-increasing / non-uniform time and NaN). Throws InputError naming
// the recording when the input has no excitation or the options do not fit the data.
ExperimentData prepare_data(const Recording& recording, const DataOptions& options = {});

// The first `n` samples of an experiment (all of it when shorter), operating point unchanged.
ExperimentData leading_samples(const ExperimentData& data, std::size_t n);

// Block averages of `factor` consecutive samples (the last, partial block dropped unless it is the
// only one): a copy at period factor·h that keeps the whole record's slow dynamics, for searches
// that need not resolve every sample. Operating point unchanged.
ExperimentData block_average(const ExperimentData& data, std::size_t factor);

// A gain in mm/mm (or mm/(mm·s)) times this is the gain in the recording's declared units
// (y_unit per u_unit): u_scale / y_scale.
double declared_gain_factor(const ExperimentData& data);
// "y_unit/u_unit", e.g. "mm/counts" ("mm/mm" without declarations).
std::string declared_gain_unit(const ExperimentData& data);

// Reads a recording and prepares it (the everyday entry point for files).
ExperimentData load_experiment(const std::string& file, const DataOptions& options = {});

// Throws InputError ("FILE: model M needs y_up_mm …") when `data` has no upstream level.
void require_upstream_level(const ExperimentData& data, const std::string& model_name);

}  // namespace canalsim::reduced
