// Where a calibrated model's level residual lives, and which model-form choice removes which
// part of it. A coefficient removes an error everywhere a little; an error of the model's form
// sits somewhere: at one operating point or flow regime, at one end of a recording's level range
// (a static-gain error that a constant coefficient cannot remove), in the seconds after a command
// switch (the dynamics), or in one frequency band. The residual r = recorded − model of every
// level channel is grouped along five axes:
//
//   operating point   each recording (validation recordings marked)
//   regime            free or submerged flow by the paper's conditions (8)/(10), as the
//                     calibrated model has it at each sample (when the replay gives a regime)
//   level             each recording and channel's own thirds of the recorded level
//   after a switch    time since the command last changed, in thirds over every series (the
//                     edges in the group's name: "< 0.5 s", "0.5 s to 1.4 s", "> 1.4 s"; samples
//                     before the first switch count as the longest)
//   frequency         a moving-average filter bank, r = slow + mid + fast with
//                     slow = MA_20s(r), mid = MA_2s(r) − MA_20s(r), fast = r − MA_2s(r)
//                     (centred averages over 20 s and 2 s: periods above ~20 s, 2–20 s, below ~2 s)
//
// Each group carries its RMS and mean (a mean comparable to the RMS is a static error), and, for
// each model-form choice refitted (model_form.hpp), the share of the group's squared residual
// the refitted model removes, 1 − Σr²_choice / Σr²: measured by refitting, not guessed. A
// negative share is a part the choice fits worse.
#pragma once

#include <string>
#include <vector>

namespace canalsim::calibration {

struct Series;

struct BreakdownGroup {
  std::string axis;   // "operating point", "regime", "level", "after a switch", "frequency"
  std::string name;   // "op1", "op3b (validation)", "low third", "< 0.5 s", "slow (> 20 s)"
  std::size_t samples = 0;
  double rms_mm = 0.0;   // RMS of the level residual in the group
  double mean_mm = 0.0;  // its mean, recorded − model
  std::vector<double> removed;  // one per ResidualBreakdown::choices
};

struct ResidualBreakdown {
  std::vector<std::string> choices;  // the choices whose shares BreakdownGroup::removed holds
  std::vector<BreakdownGroup> groups;
};

// A model-form choice's refit: its name and the series of its calibrated model, the same
// recordings and channels as the model broken down.
struct ChoiceSeries {
  std::string name;
  const std::vector<Series>* series = nullptr;
};

// The breakdown of `series` (Calibration::series: recorded and calibrated levels; channels other
// than levels are left out), with each choice's share. A choice whose series do not match the
// model's (another recording, channel or length) gets NaN shares.
ResidualBreakdown residual_breakdown(const std::vector<Series>& series, const std::vector<ChoiceSeries>& choices = {});

// The edge between the filter bank's fast band and the slower ones [s], and the part of a
// residual sampled every `period_s` slower than it: slow + mid = MA_2s(r). A model's error from
// how its scheme resolves bores lives in the fast band; a change of the canal the model lacks
// (a gate's play, a leak) moves the levels over the command's slower swings as well.
constexpr double fast_band_edge_s = 2.0;
std::vector<double> slower_than_fast_band(const std::vector<double>& residual, double period_s);

// What the calibrated model leaves of a series: recorded − calibrated, sample by sample (the
// series must carry both, of one length).
std::vector<double> calibrated_residual(const Series& series);

}  // namespace canalsim::calibration
