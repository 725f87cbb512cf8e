// Identification at any time scale: first-order-plus-delay step responses written in
// closed form, y(t) = y0 + K A (1 − e^{−(t − t_step − L)/T}) after t_step + L, with noise and a
// sensor that quantises with an offset, sampled at 0.125 s and at 0.01 s, for time constants of
// 2 s to 5 min and delays of 0.5 to 12 s. The fitted LIOM must recover K and T within 5 %; L
// within two samples wherever the Cramér–Rao bound allows it (two samples ≥ 3 bound std), else
// within 3 bound std, with the least-squares criterion (DelayPrecision.*, the bound computed
// independently in crb.hpp); the paper's IAE fit (the default) within max(2 samples, T/250). The
// models nested in others never fit better than the models containing them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "reduced_models/frequency.hpp"
#include "tests/reduced_models/crb.hpp"
#include "reduced_models/identification.hpp"
#include "testing/recordings.hpp"
#include "testing/synthetic.hpp"

namespace canalsim::reduced {
namespace {

struct StepTest {
  double K, T, L, h;
  std::size_t step_sample = 40;  // u steps at this sample
};

// A gate step of kA = 5 mm from 20 mm at t_step, n samples every h: the level 45 mm plus
// `response(t − t_step − L)` once that is positive (a closed form), read by a level sensor with
// noise σ = 0.03 mm and resolution 0.1 mm on a grid offset by 0.037 mm (a sensor zero that is not
// a multiple of the resolution) seeded with `seed`, or exactly without one.
constexpr double kA = 5.0;

template <class Response>
Recording step_recording(const std::string& source, std::size_t n, double h, double t_step, double L,
                         std::optional<unsigned> seed, Response response) {
  const double u0 = 20.0, y0 = 45.0, r = 0.1, offset = 0.037;
  std::mt19937 rng(seed.value_or(0));
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<double> t(n), u(n), y(n);
  for (std::size_t k = 0; k < n; ++k) {
    t[k] = static_cast<double>(k) * h;
    u[k] = t[k] >= t_step - 1e-9 ? u0 + kA : u0;
    const double since = t[k] - t_step - L;
    const double level = y0 + (since > 0.0 ? response(since) : 0.0);
    y[k] = seed ? r * std::round((level + noise(rng) - offset) / r) + offset : level;
  }
  return testing::command_and_level(source, std::move(t), std::move(u), std::move(y));
}

// The first-order-plus-delay step of `s`, long enough to settle (five time constants after the
// delay), read by the noisy quantising sensor.
Recording fopdt_step_recording(const StepTest& s, unsigned seed = 3) {
  const double t_step = static_cast<double>(s.step_sample) * s.h;
  const auto n = static_cast<std::size_t>(std::ceil((t_step + s.L + 5.0 * s.T + 5.0) / s.h));
  return step_recording("fopdt.csv", n, s.h, t_step, s.L, seed,
                        [&s](double since) { return s.K * kA * (1.0 - std::exp(-since / s.T)); });
}

// The paper's IAE fit: K and T within 5 %; L within two samples, or T/250 when that is longer.
// The IAE estimate of L is less precise than least squares' (Monte Carlo over 20 seeds at
// 0.01 s: rms error 0.05 s for T = 60 s and 0.25–0.28 s for T = 300 s, against Cramér–Rao bounds
// of 0.01–0.025 s and 0.036–0.12 s; docs/reduced-models.md, "Delay precision"): the L1 cost is
// statistically less efficient, y0 is taken from the 40 samples before the step instead of being
// fitted, and the quantised readings bias it. That the search is not trapped is shown by the IAE:
// at most 2 % above that of the true model (often below it).
void expect_fopdt_recovered(const StepTest& s) {
  SCOPED_TRACE("T " + std::to_string(s.T) + " s, L " + std::to_string(s.L) + " s, h " +
               std::to_string(s.h) + " s");
  const auto data = prepare_data(fopdt_step_recording(s));
  const auto r = fit(ModelKind::liom, data);
  EXPECT_NEAR(r.model.p.K, s.K, 0.05 * s.K);
  EXPECT_NEAR(r.model.p.T, s.T, 0.05 * s.T);
  EXPECT_NEAR(r.model.p.L, s.L, std::max(2.0 * s.h, s.T / 250.0));
  Model truth{ModelKind::liom, {}, {}};
  testing::set_parameters(truth, {{"K", s.K}, {"T", s.T}, {"L", s.L}});
  EXPECT_LE(r.iae_total, 1.02 * validate_model(truth, data).iae);
  EXPECT_GT(r.nrmse.front(), 90.0);
}

TEST(TimeScale, FopdtStepResponsesAreRecoveredAtAQuarterSecondSampling) {
  for (const StepTest s : {StepTest{2.0, 2.0, 1.5, 0.125}, StepTest{2.0, 2.0, 12.0, 0.125},
                           StepTest{2.0, 20.0, 1.5, 0.125}, StepTest{0.7, 20.0, 0.5, 0.125},
                           StepTest{2.0, 60.0, 1.5, 0.125}, StepTest{1.3, 60.0, 6.0, 0.125},
                           StepTest{2.0, 300.0, 12.0, 0.125}, StepTest{2.0, 300.0, 0.5, 0.125}}) {
    expect_fopdt_recovered(s);
  }
}

TEST(TimeScale, FopdtStepResponsesAreRecoveredAtTenMillisecondSampling) {
  for (const StepTest s : {StepTest{2.0, 2.0, 1.5, 0.01}, StepTest{2.0, 20.0, 12.0, 0.01},
                           StepTest{2.0, 60.0, 0.5, 0.01}, StepTest{2.0, 300.0, 3.0, 0.01}}) {
    expect_fopdt_recovered(s);
  }
}

// ---- Delay precision: the Cramér–Rao bound (crb.hpp) and the least-squares polish ----------

// The bound on the delay of the recording fopdt_step_recording(s) makes, with the operating
// point y0 estimated jointly with K, T and L (prepare_data takes y0 from the samples before the
// step: no estimator knows it).
double delay_bound(const StepTest& s) {
  testing_crb::FopdtExperiment e{s.K, s.T, s.L};
  e.h = s.h;
  e.t_step = static_cast<double>(s.step_sample) * s.h;
  e.n = fopdt_step_recording(s).column("t_s").size();
  return testing_crb::crb_std(e, true)(2);
}

// L within two samples where the bound allows it (two samples ≥ 3 bound std), else within
// 3 bound std; K and T within 5 %.
void expect_delay_at_the_bound(const StepTest& s) {
  const double bound = delay_bound(s), tolerance = std::max(2.0 * s.h, 3.0 * bound);
  SCOPED_TRACE("T " + std::to_string(s.T) + " s, L " + std::to_string(s.L) + " s, h " + std::to_string(s.h) +
               " s: CRB std of L " + std::to_string(bound) + " s");
  FitOptions o;
  o.criterion = Criterion::least_squares;
  const auto r = fit(ModelKind::liom, prepare_data(fopdt_step_recording(s)), o);
  EXPECT_NEAR(r.model.p.K, s.K, 0.05 * s.K);
  EXPECT_NEAR(r.model.p.T, s.T, 0.05 * s.T);
  EXPECT_NEAR(r.model.p.L, s.L, tolerance);
}

// Which side of two samples three bound std of a case's delay lie.
enum class Bound { within_two_samples, wider_than_two_samples };

// Each case's bound is on the side `bound` says, and its delay is recovered to it.
void expect_delays_at_the_bound(const std::vector<StepTest>& cases, Bound bound) {
  for (const StepTest& s : cases) {
    if (bound == Bound::within_two_samples) {
      EXPECT_LE(3.0 * delay_bound(s), 2.0 * s.h);
    } else {
      EXPECT_GT(3.0 * delay_bound(s), 2.0 * s.h);
    }
    expect_delay_at_the_bound(s);
  }
}

// Where two samples are at least three bound std, L is recovered within two samples: every
// case at 0.125 s up to T = 60 s, at 0.01 s the fast pools and T = 20 s with L ≥ 3 s.
TEST(DelayPrecision, TheDelayIsWithinTwoSamplesWhereTheCramerRaoBoundAllowsIt) {
  expect_delays_at_the_bound({{2.0, 2.0, 0.5, 0.125}, {2.0, 20.0, 3.0, 0.125}, {2.0, 60.0, 12.0, 0.125},
                              {1.3, 60.0, 0.5, 0.125}, {2.0, 2.0, 12.0, 0.01}, {2.0, 20.0, 3.0, 0.01},
                              {2.0, 20.0, 12.0, 0.01}},
                             Bound::within_two_samples);
}

// Where the bound is wider than two samples (slow pools: the level leaves y0 at K A/T mm/s, under
// the 0.03 mm noise and 0.1 mm resolution), L is recovered within three bound std.
TEST(DelayPrecision, ASlowPoolsDelayIsWithinThreeCramerRaoStdWhereThatIsWiderThanTwoSamples) {
  expect_delays_at_the_bound({{2.0, 300.0, 0.5, 0.125}, {2.0, 300.0, 12.0, 0.125}, {2.0, 20.0, 0.5, 0.01},
                              {2.0, 60.0, 0.5, 0.01}, {2.0, 60.0, 12.0, 0.01}, {2.0, 300.0, 3.0, 0.01},
                              {2.0, 300.0, 12.0, 0.01}},
                             Bound::wider_than_two_samples);
}

// The bound's ingredients: a fine quantiser loses no information (1/σ² per sample), a coarse one
// loses some on average over the level; and the unknown operating point widens the delay's bound.
TEST(DelayPrecision, TheBoundsIngredientsBehaveAsTheTheorySays) {
  EXPECT_NEAR(testing_crb::sample_information(45.01, 0.03, 0.001, 0.0), 1.0 / (0.03 * 0.03), 1e-3 / (0.03 * 0.03));
  double mean = 0.0;
  for (int i = 0; i < 100; ++i) mean += testing_crb::sample_information(45.0 + 0.001 * i, 0.03, 0.1, 0.037) / 100.0;
  EXPECT_LT(mean, 1.0 / (0.03 * 0.03));
  testing_crb::FopdtExperiment e{2.0, 20.0, 3.0};
  e.h = 0.01;
  e.t_step = 0.4;
  e.n = 12000;
  e.quantum = 0.0;
  const double known_y0 = testing_crb::crb_std(e, false)(2), unknown_y0 = testing_crb::crb_std(e, true)(2);
  EXPECT_LT(known_y0, unknown_y0);
  e.sigma *= 2.0;  // without a quantiser the bound scales with the noise
  EXPECT_NEAR(testing_crb::crb_std(e, true)(2), 2.0 * unknown_y0, 1e-9 * unknown_y0);
}

// Coarse sampling does not bias the fit: the exact zero-order hold (zoh.hpp) makes the LIOM the
// continuous model sampled, so a clean closed-form response at 0.125 s and at 1 s (backward
// Euler read it one sample late with T low by h/2) gives L within a tenth of a sample and T
// within 1 %.
TEST(TimeScale, CoarseSamplingDoesNotBiasTheDelayOrTheTimeConstant) {
  for (const double h : {0.125, 1.0}) {
    for (const double T : {3.0, 20.0}) {
      SCOPED_TRACE("h " + std::to_string(h) + " s, T " + std::to_string(T) + " s");
      const double L = 3.3, K = 2.0, t_step = 10.0 * h;
      const auto n = static_cast<std::size_t>((t_step + L + 8.0 * T) / h);
      const Recording rec = step_recording("clean.csv", n, h, t_step, L, std::nullopt,
                                           [&](double since) { return K * kA * (1.0 - std::exp(-since / T)); });
      const auto r = fit(ModelKind::liom, prepare_data(rec));
      EXPECT_NEAR(r.model.p.L, L, 0.1 * h);
      EXPECT_NEAR(r.model.p.T, T, 0.01 * T);
      EXPECT_NEAR(r.model.p.K, K, 0.01 * K);
    }
  }
}

TEST(TimeScale, AStepAtTheRecordingsSecondSampleFits) {
  StepTest s{2.0, 20.0, 1.5, 0.125};
  s.step_sample = 1;
  expect_fopdt_recovered(s);
}

// The canal-control models from their own closed-form step responses: ID (Schuurmans et al.
// 1999), Δy = K A (t − t_step − L), and IDZ (Litrico & Fromion 2004), Δy = K A (t − t_step − L +
// Tz) after t_step + L; K in mm/(mm·s). Same sensor as above, 0.125 s sampling, 300 s.
Recording integrator_step_recording(double K, double Tz, double L, double h) {
  return step_recording("integrator.csv", static_cast<std::size_t>(300.0 / h), h, 5.0, L, 5u,
                        [&](double since) { return K * kA * (since + Tz); });
}

// On a ramp a delay error is a level offset: the operating point y0 (mean of the quantised rest
// samples) is known to about 0.01 mm here, i.e. 0.1 s of delay on the 0.1 mm/s ramp. So L is
// held to two samples at 0.125 s, and at 0.01 s to 0.15 s together with an IAE at most that of
// the true model (the fit there is 0.107 s late with an IAE 3 % below the truth's).
TEST(CanalControlModels, IntegratorDelayIsRecoveredFromItsClosedFormStepResponse) {
  for (const double L : {0.5, 4.0, 12.0}) {
    for (const double h : {0.125, 0.01}) {
      SCOPED_TRACE("L " + std::to_string(L) + " s, h " + std::to_string(h) + " s");
      const auto data = prepare_data(integrator_step_recording(0.02, 0.0, L, h));
      const auto r = fit(ModelKind::id, data);
      EXPECT_NEAR(r.model.p.K, 0.02, 0.05 * 0.02);
      EXPECT_NEAR(r.model.p.L, L, std::max(2.0 * h, 0.15));
      Model truth{ModelKind::id, {}, {}};
      truth.p.K = 0.02;
      truth.p.L = L;
      EXPECT_LE(r.iae_total, validate_model(truth, data).iae);
      EXPECT_GT(r.nrmse.front(), 90.0);
    }
  }
}

TEST(CanalControlModels, IntegratorDelayZeroIsRecoveredFromItsClosedFormStepResponse) {
  for (const double Tz : {10.0, 40.0}) {
    for (const double L : {1.5, 8.0}) {
      SCOPED_TRACE("Tz " + std::to_string(Tz) + " s, L " + std::to_string(L) + " s");
      const auto r = fit(ModelKind::idz, prepare_data(integrator_step_recording(0.02, Tz, L, 0.125)));
      EXPECT_NEAR(r.model.p.K, 0.02, 0.05 * 0.02);
      EXPECT_NEAR(r.model.p.Tz, Tz, 0.05 * Tz);
      EXPECT_NEAR(r.model.p.L, L, 2.0 * 0.125);
      EXPECT_GT(r.nrmse.front(), 90.0);
    }
  }
}

TEST(CanalControlModels, IdzNeverFitsWorseThanIdWhichItContains) {
  const auto data = prepare_data(fopdt_step_recording(StepTest{2.0, 60.0, 3.0, 0.125}));
  EXPECT_LE(fit(ModelKind::idz, data).iae_total, fit(ModelKind::id, data).iae_total * (1.0 + 1e-9));
}

// Their transfer functions: ID K e^{−Ls}/s (gain K/ω, phase −π/2 − ωL) and IDZ K (1/s + Tz) e^{−Ls}
// (gain K √(1/ω² + Tz²), tending to the direct gain K·Tz at high frequency).
TEST(CanalControlModels, FrequencyResponsesAreTheIntegratorsAndTheZeros) {
  Model id{ModelKind::id, {}, {}};
  id.p.K = 0.02;
  id.p.L = 4.0;
  const double omega = 0.3;
  const auto g = frequency_response(id, OperatingPoint{}, omega);
  EXPECT_NEAR(std::abs(g), 0.02 / omega, 1e-12);
  EXPECT_NEAR(std::remainder(std::arg(g) - (-std::numbers::pi / 2.0 - omega * 4.0), 2.0 * std::numbers::pi), 0.0, 1e-12);
  Model idz = id;
  idz.kind = ModelKind::idz;
  idz.p.Tz = 40.0;
  EXPECT_NEAR(std::abs(frequency_response(idz, OperatingPoint{}, omega)),
              0.02 * std::sqrt(1.0 / (omega * omega) + 1600.0), 1e-12);
  EXPECT_NEAR(std::abs(frequency_response(idz, OperatingPoint{}, 1e4)), 0.02 * 40.0, 1e-4);
}

// Data none of the nested models represents exactly: two lags in series, the gain following the
// upstream level.
ExperimentData two_lags_with_upstream_gain() {
  Model truth{ModelKind::sopd, {}, {}};
  testing::set_parameters(truth, {{"K", 0.8}, {"T", 3.0}, {"T2", 0.8}, {"L", 2.5}});
  testing::SyntheticSpec spec;
  spec.n = 1500;
  spec.y_up_swing = 8.0;
  return prepare_data(testing::synthetic_recording(truth, spec));
}

// Of each (outer, inner) pair the outer model, which contains the inner one, fits at least as
// well: its cost is at most the inner one's (to rounding).
void expect_no_worse_than_contained(std::map<ModelKind, double>& cost,
                                    const std::vector<std::pair<ModelKind, ModelKind>>& pairs) {
  for (const auto& [outer, inner] : pairs) {
    EXPECT_LE(cost[outer], cost[inner] * (1.0 + 1e-9)) << model_name(outer) << " vs " << model_name(inner);
  }
}

// Every pair of nested models on data none of them represents exactly (two lags in series, the
// gain following the upstream level): the model that contains another fits at least as well.
TEST(NestedModels, AModelNeverFitsWorseThanAModelItContains) {
  const ExperimentData data = two_lags_with_upstream_gain();
  FitOptions o;
  o.actuation.quantum_mm = 0.05;
  std::map<ModelKind, double> iae;
  for (auto kind : {ModelKind::liom, ModelKind::lfom, ModelKind::nliom_f, ModelKind::nliom_s,
                    ModelKind::nlfom_f, ModelKind::nlfom_s}) {
    iae[kind] = fit(kind, data, o).iae_total;
  }
  const std::vector<std::pair<ModelKind, ModelKind>> pairs = {
      {ModelKind::lfom, ModelKind::liom},     {ModelKind::nliom_f, ModelKind::liom},
      {ModelKind::nliom_s, ModelKind::liom},  {ModelKind::nlfom_f, ModelKind::nliom_f},
      {ModelKind::nlfom_f, ModelKind::lfom},  {ModelKind::nlfom_f, ModelKind::liom},
      {ModelKind::nlfom_s, ModelKind::nliom_s}, {ModelKind::nlfom_s, ModelKind::lfom},
      {ModelKind::nlfom_s, ModelKind::liom}};
  expect_no_worse_than_contained(iae, pairs);
}

// The same under the least-squares criterion (its sum of squares, with the fitted offsets and the
// sensor's mean reading), for the models it polishes.
TEST(NestedModels, UnderLeastSquaresAModelNeverFitsWorseThanAModelItContains) {
  const ExperimentData data = two_lags_with_upstream_gain();
  FitOptions o;
  o.criterion = Criterion::least_squares;
  std::map<ModelKind, double> cost;
  for (auto kind : {ModelKind::liom, ModelKind::lfom, ModelKind::nliom_f, ModelKind::nlfom_f}) {
    cost[kind] = fit(kind, data, o).cost_total;
  }
  const std::vector<std::pair<ModelKind, ModelKind>> pairs = {
      {ModelKind::lfom, ModelKind::liom}, {ModelKind::nliom_f, ModelKind::liom},
      {ModelKind::nlfom_f, ModelKind::nliom_f}, {ModelKind::nlfom_f, ModelKind::lfom}};
  expect_no_worse_than_contained(cost, pairs);
}

}  // namespace
}  // namespace canalsim::reduced
