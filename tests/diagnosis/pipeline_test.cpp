// The pipeline's rules for a residual as large as a calibrated model's own error. That error on a
// canal comes mostly from how its scheme resolves the bores each gate move sends down the pool —
// sample-long spikes whose sign and size depend on where between two samples the bore passed —
// while a change of the canal the model lacks moves the levels over the command's slower swings.
// A residual as large as the model's error in total is then ordinary when it is fast, and not when
// a part of it is slow. The model's error here is drawn as such spikes (not from the code's own
// scheme), the change as a gain on the level's response, the shape a gate's play gives. A change
// seen only in the slower part is named by the candidate that explains that part (step 4's second
// route), and left unexplained when no candidate does.
#include "diagnosis/pipeline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "calibration/residual_breakdown.hpp"

namespace canalsim::diagnosis {
namespace {

constexpr double h = 0.13;  // the canal's sampling period [s]
constexpr std::size_t samples = 1966;
constexpr double noise_mm = 0.02;

struct Lab {
  std::vector<double> u, response;  // command and the level's response to it [mm]
};

// A PRBS-like command on a half-second clock sampled every h, and a first-order response to it
// (time constant 0.3 s: the bores arrive within a sample or two; gain 0.4) around 50 mm.
Lab lab(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution up(0.5);
  Lab l;
  double level = 15.0, y = 0.0;
  for (std::size_t k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) * h;
    if (std::floor(t / 0.5) != std::floor((t - h) / 0.5) && up(rng)) level = level > 15.0 ? 10.0 : 20.0;
    l.u.push_back(level);
    y += (h / 0.3) * (0.4 * (level - 15.0) - y);
    l.response.push_back(y);
  }
  return l;
}

// The model's error from resolving bores: at each command switch a one-sample spike of random
// sign and size (a bore passing early or late within the sample), 0.03 mm per mm of the jump.
std::vector<double> bore_spikes(const Lab& l, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> size(0.0, 0.03);
  std::vector<double> e(samples, 0.0);
  for (std::size_t k = 1; k + 1 < samples; ++k) {
    if (l.u[k] != l.u[k - 1]) e[k + 1] = size(rng) * std::abs(l.u[k] - l.u[k - 1]);
  }
  return e;
}

std::vector<double> white(double std, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, std);
  std::vector<double> v(samples);
  for (double& x : v) x = n(rng);
  return v;
}

// One recording: y_dwe_mm (primary) carries the model's error alone, y_dw_mm the model's error plus
// `change` (its residual), each with the sensor's noise. The recorded levels, from which the
// pipeline estimates that noise, are a smooth swing around 50 mm with the same noise.
RecordingResiduals recording(const Lab& l, const std::vector<double>& change, std::uint64_t seed) {
  RecordingResiduals r;
  r.name = "op" + std::to_string(seed);
  r.period_s = h;
  r.u = l.u;
  r.primary = "y_dwe_mm";
  for (std::size_t k = 0; k < samples; ++k) r.t.push_back(static_cast<double>(k) * h);
  const std::vector<double> spikes_dwe = bore_spikes(l, seed + 1), spikes_dw = bore_spikes(l, seed + 2);
  const std::vector<double> noise_dwe = white(noise_mm, seed + 3), noise_dw = white(noise_mm, seed + 4);
  for (const char* channel : {"y_dwe_mm", "y_dw_mm"}) {
    const bool dw = std::string(channel) == "y_dw_mm";
    std::vector<double> residual(samples), recorded(samples);
    for (std::size_t k = 0; k < samples; ++k) {
      residual[k] = (dw ? spikes_dw[k] + change[k] + noise_dw[k] : spikes_dwe[k] + noise_dwe[k]);
      recorded[k] = 50.0 + std::sin(0.05 * r.t[k]) + (dw ? noise_dw[k] : noise_dwe[k]);
    }
    r.residuals[channel] = residual;
    r.recorded[channel] = recorded;
  }
  r.level = r.recorded.at("y_dwe_mm");
  return r;
}

// What a calibration on the baseline `b` leaves, times √2, as DiagnoseOptions turns it into the
// pipeline's settings: in total and in the part slower than the fast band.
PipelineSettings settings_from_baseline(const std::vector<RecordingResiduals>& b) {
  PipelineSettings s;
  for (const char* channel : {"y_dwe_mm", "y_dw_mm"}) {
    double total = 0.0, slow = 0.0, n = 0.0;
    for (const auto& r : b) {
      const auto& e = r.residuals.at(channel);
      for (double v : e) total += v * v;
      for (double v : calibration::slower_than_fast_band(e, h)) slow += v * v;
      n += static_cast<double>(e.size());
    }
    s.tolerated_by_channel[channel] = std::numbers::sqrt2 * std::sqrt(total / n);
    s.tolerated_slow_by_channel[channel] = std::numbers::sqrt2 * std::sqrt(slow / n);
  }
  return s;
}

// The change of a response `share` smaller.
std::vector<double> shrunk(const Lab& l, double share) {
  std::vector<double> change(samples);
  for (std::size_t k = 0; k < samples; ++k) change[k] = -share * l.response[k];
  return change;
}

const ChannelFigures& channel(const Diagnosis& d, const std::string& name) {
  for (const auto& c : d.channels) {
    if (c.name == name) return c;
  }
  throw std::runtime_error("no channel " + name);
}

TEST(OrdinaryChannel, AResidualAsLargeAsTheModelsErrorIsOrdinaryWhenFastAndNotWhenPartlySlow) {
  const std::vector<double> nothing(samples, 0.0);
  const Lab base1 = lab(1), base2 = lab(2), trial1 = lab(11), trial2 = lab(12);
  const PipelineSettings settings =
      settings_from_baseline({recording(base1, nothing, 100), recording(base2, nothing, 200)});

  // Another draw of the command, the spikes and the noise: ordinary in total and in the slow part.
  Diagnosis clean;
  set_noise_figures({recording(trial1, nothing, 300), recording(trial2, nothing, 400)}, 0.0, settings, clean);
  const ChannelFigures& c = channel(clean, "y_dw_mm");
  ASSERT_GT(c.tolerated, 3.0 * c.noise);  // the model's error, not the noise, sets what is ordinary
  EXPECT_LE(c.rms, c.tolerated);
  EXPECT_LE(c.slow_rms, c.slow_tolerated);
  EXPECT_TRUE(c.ordinary);
  EXPECT_LT(c.slow_rms, 0.4 * c.rms);  // the model's error is fast

  // The level's response 6 % smaller (a gate's play shrinking its swing): within √2 times the
  // model's error in total, beyond it in the slow part.
  const std::vector<RecordingResiduals> changed = {recording(trial1, shrunk(trial1, 0.06), 300),
                                                   recording(trial2, shrunk(trial2, 0.06), 400)};
  Diagnosis with_change;
  set_noise_figures(changed, 0.0, settings, with_change);
  const ChannelFigures& w = channel(with_change, "y_dw_mm");
  EXPECT_LE(w.rms, w.tolerated);
  EXPECT_GT(w.rms, 1.1 * c.rms);
  EXPECT_GT(w.slow_rms, 1.3 * w.slow_tolerated);
  EXPECT_FALSE(w.ordinary);
  EXPECT_TRUE(channel(with_change, "y_dwe_mm").ordinary);
  EXPECT_FALSE(set_verdict(with_change, settings.none_noise_factor));
  EXPECT_EQ(with_change.verdict, "unexplained");
  EXPECT_NE(with_change.reason.find("y_dw_mm"), std::string::npos) << with_change.reason;
  EXPECT_NE(with_change.reason.find("exceeds what the calibration tolerates in its part slower than 2 s"), std::string::npos)
      << with_change.reason;

  // Judged in total alone, the same change passes for the model's own error.
  PipelineSettings total_only = settings;
  total_only.tolerated_slow_by_channel.clear();
  Diagnosis in_total;
  set_noise_figures(changed, 0.0, total_only, in_total);
  EXPECT_TRUE(channel(in_total, "y_dw_mm").ordinary);
  EXPECT_FALSE(set_verdict(in_total, total_only.none_noise_factor));
  EXPECT_EQ(in_total.verdict, "none");
}

// Candidates of known shapes (the scenario engine re-simulates instead): each fits θ·shape to
// y_dw_mm's residual by least squares on the first half of every recording and is judged as the
// engine judges — held-out cost balanced over the level channels, in total and in the part slower
// than the fast band, BIC on the fitted half, a material θ, a held-out fit that improves.
class ShapeExplainer final : public Explainer {
 public:
  ShapeExplainer(std::vector<RecordingResiduals> sets, std::map<std::string, std::vector<std::vector<double>>> shapes)
      : sets_(std::move(sets)), shapes_(std::move(shapes)) {}

  std::vector<RecordingResiduals> nominal_residuals() override { return sets_; }
  double sensor_resolution() const override { return 0.0; }
  std::vector<RecordingSeries> series_with(const std::string&) const override { return {}; }

  EffectResult explain(const std::string& candidate) override {
    const auto& shape = shapes_.at(candidate);
    double rs = 0.0, ss = 0.0;
    for (std::size_t i = 0; i < sets_.size(); ++i) {
      const auto& r = sets_[i].residuals.at("y_dw_mm");
      for (std::size_t k = 0; k < sets_[i].fit_samples; ++k) {
        rs += r[k] * shape[i][k];
        ss += shape[i][k] * shape[i][k];
      }
    }
    theta_[candidate] = rs / ss;
    const std::vector<RecordingResiduals> after = residuals_with(candidate);
    EffectResult e;
    e.name = candidate;
    e.parameter = {"theta", "-", theta_[candidate], 0.0};
    e.cost_before = cost(sets_, false, false);
    e.cost_after = cost(after, false, false);
    e.heldout_cost_before = cost(sets_, true, false);
    e.heldout_cost_after = cost(after, true, false);
    e.heldout_slow_cost_before = cost(sets_, true, true);
    e.heldout_slow_cost_after = cost(after, true, true);
    e.score = 1.0 - e.heldout_cost_after / e.heldout_cost_before;
    e.slow_score = 1.0 - e.heldout_slow_cost_after / e.heldout_slow_cost_before;
    e.delta_bic = bic_change(static_cast<double>(samples), e.cost_before, e.cost_after);
    e.material = std::abs(theta_[candidate]) > 0.01;
    e.heldout_improves = e.heldout_cost_after < e.heldout_cost_before;
    e.significant = is_significant(e, rule);
    return e;
  }

  std::vector<RecordingResiduals> residuals_with(const std::string& effect) const override {
    std::vector<RecordingResiduals> out = sets_;
    if (effect.empty()) return out;
    for (std::size_t i = 0; i < out.size(); ++i) {
      auto& r = out[i].residuals.at("y_dw_mm");
      for (std::size_t k = 0; k < r.size(); ++k) r[k] -= theta_.at(effect) * shapes_.at(effect)[i][k];
    }
    return out;
  }

  const SignificanceRule rule{0.15, 10.0, true};

 private:
  // Mean over the level channels of the mean square on the fitted or held-out halves (or their
  // part slower than the fast band), each over the nominal model's.
  double cost(const std::vector<RecordingResiduals>& sets, bool heldout, bool slow) const {
    double sum = 0.0;
    for (const char* channel : {"y_dwe_mm", "y_dw_mm"}) sum += mean_square(sets, channel, heldout, slow) / mean_square(sets_, channel, heldout, slow);
    return sum / 2.0;
  }
  static double mean_square(const std::vector<RecordingResiduals>& sets, const std::string& channel, bool heldout, bool slow) {
    double sq = 0.0, n = 0.0;
    for (const auto& r : sets) {
      const auto& e = r.residuals.at(channel);
      const auto split = static_cast<std::ptrdiff_t>(r.fit_samples);
      std::vector<double> part = heldout ? std::vector<double>(e.begin() + split, e.end()) : std::vector<double>(e.begin(), e.begin() + split);
      if (slow) part = calibration::slower_than_fast_band(part, h);
      for (double v : part) sq += v * v;
      n += static_cast<double>(part.size());
    }
    return sq / n;
  }

  std::vector<RecordingResiduals> sets_;
  std::map<std::string, std::vector<std::vector<double>>> shapes_;
  std::map<std::string, double> theta_;
};

TEST(OrdinaryChannel, AChangeSeenOnlySlowerThanTheModelsErrorIsNamedByTheCandidateThatExplainsThatPart) {
  const std::vector<double> nothing(samples, 0.0);
  const Lab base1 = lab(1), base2 = lab(2), trial1 = lab(11), trial2 = lab(12);
  PipelineSettings settings = settings_from_baseline({recording(base1, nothing, 100), recording(base2, nothing, 200)});
  // A response 4 % smaller: in total, the model's own error hides it from every candidate's score.
  constexpr double share = 0.04;
  std::vector<RecordingResiduals> changed = {recording(trial1, shrunk(trial1, share), 300),
                                             recording(trial2, shrunk(trial2, share), 400)};
  for (auto& r : changed) r.fit_samples = samples / 2;
  // The candidates: the level's response (the change's own shape) and a constant offset.
  std::map<std::string, std::vector<std::vector<double>>> shapes;
  shapes["response_gain"] = {trial1.response, trial2.response};
  shapes["offset"] = {std::vector<double>(samples, 1.0), std::vector<double>(samples, 1.0)};

  ShapeExplainer explainer(changed, shapes);
  settings.significance = explainer.rule;
  const Diagnosis d = run_pipeline(explainer, {"offset", "response_gain"}, settings);
  ASSERT_TRUE(d.ok) << d.message;
  EXPECT_EQ(d.verdict, "response_gain") << d.reason;
  ASSERT_FALSE(d.effects.empty());
  const EffectResult& named = d.effects.front();
  EXPECT_EQ(named.name, "response_gain");
  // In total the model's own error keeps its score below the rule; in the slower part it passes.
  EXPECT_LT(named.score, explainer.rule.min_score);
  EXPECT_GE(named.slow_score, explainer.rule.min_score);
  EXPECT_NEAR(named.parameter.value, -share, 0.01);
  EXPECT_NE(d.reason.find("slower than 2 s"), std::string::npos) << d.reason;
  EXPECT_FALSE(d.unexplained.has_value()) << d.unexplained->summary;

  // An offset cannot make the slower part ordinary: with it alone, the residual stays unexplained.
  ShapeExplainer offset_only(changed, shapes);
  const Diagnosis u = run_pipeline(offset_only, {"offset"}, settings);
  ASSERT_TRUE(u.ok) << u.message;
  EXPECT_EQ(u.verdict, "unexplained") << u.reason;
  ASSERT_EQ(u.effects.size(), 1u);
  EXPECT_NE(u.effects.front().set_aside.find("slower than 2 s"), std::string::npos) << u.effects.front().set_aside;
  ASSERT_TRUE(u.unexplained.has_value());
  EXPECT_EQ(u.unexplained->channel, "y_dw_mm");
}

TEST(OrdinaryChannel, TheSlowPartsToleranceIsNeverBelowWhatTheNoiseLeavesInIt) {
  // A baseline whose slow part is nothing: white noise averaged over 2 s still leaves
  // noise × sqrt(h / 2 s) in it, and three times that is tolerated.
  PipelineSettings s;
  s.tolerated_by_channel = {{"y_dwe_mm", 1.0}, {"y_dw_mm", 1.0}};
  s.tolerated_slow_by_channel = {{"y_dwe_mm", 0.0}, {"y_dw_mm", 0.0}};
  const std::vector<double> nothing(samples, 0.0);
  Diagnosis d;
  set_noise_figures({recording(lab(5), nothing, 500)}, 0.0, s, d);
  const ChannelFigures& c = channel(d, "y_dwe_mm");
  EXPECT_NEAR(c.noise, noise_mm, 0.1 * noise_mm);
  EXPECT_NEAR(c.slow_tolerated, s.none_noise_factor * c.noise * std::sqrt(h / calibration::fast_band_edge_s), 1e-12);
}

}  // namespace
}  // namespace canalsim::diagnosis
