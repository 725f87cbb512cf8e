// Tests of reduced_models/models.*: model definitions, nonlinear input terms, rate limit and
// quantisation, hybrid switching.
#include "reduced_models/models.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "reduced_models/sensor_reading.hpp"
#include "testing/synthetic.hpp"

namespace canalsim::reduced {
namespace {

ExperimentData step_data(std::size_t n, double h, double step_mm, std::size_t at = 0) {
  ExperimentData d;
  d.source = "step";
  d.h = h;
  for (std::size_t k = 0; k < n; ++k) {
    d.t_s.push_back(h * static_cast<double>(k));
    d.u_mm.push_back(k >= at ? 20.0 + step_mm : 20.0);
  }
  d.u0_mm = 20.0;
  d.y0_mm = 40.0;
  d.y_dwe_mm.assign(n, 40.0);
  d.y_up_mm.assign(n, 60.0);
  return d;
}

TEST(ModelNames, RoundTripAndAcceptUnderscoresAndCase) {
  for (auto kind : all_model_kinds()) EXPECT_EQ(parse_model_kind(model_name(kind)), kind);
  EXPECT_EQ(parse_model_kind("NLFOM_S"), ModelKind::nlfom_s);
  EXPECT_FALSE(parse_model_kind("arx").has_value());
}

TEST(Liom, StepSettlesAtTheGainTimesTheStepAfterTheDelay) {
  const auto d = step_data(2000, 0.13, 5.0);
  Model m{ModelKind::liom, {}, {}};
  testing::set_parameters(m, {{"K", 0.6}, {"T", 1.7}, {"L", 4.9}});
  const auto y = simulate(m, d).y_dwe_mm;
  EXPECT_NEAR(y.back(), 40.0 + 3.0, 1e-9);
  const auto delay_samples = static_cast<std::size_t>(4.9 / 0.13);  // 37.69
  for (std::size_t k = 0; k < delay_samples; ++k) EXPECT_EQ(y[k], 40.0);
  EXPECT_GT(y[delay_samples + 1], 40.0);
}

TEST(FractionalDelay, InterpolatesLinearlyBetweenSamples) {
  const std::vector<double> x{0.0, 1.0, 2.0, 3.0, 4.0};
  std::vector<double> out;
  fractional_delay(x, 1.25, out);
  EXPECT_DOUBLE_EQ(out[0], 0.0);
  EXPECT_DOUBLE_EQ(out[1], 0.0);  // between x[-1] = 0 and x[0] = 0
  EXPECT_DOUBLE_EQ(out[2], 0.75);
  EXPECT_DOUBLE_EQ(out[4], 2.75);
}

TEST(FractionalDelay, CommutesWithTheGlRecursionForLinearModels) {
  // The fitter relies on this to re-delay a cached unit response instead of re-simulating.
  const auto d = step_data(1500, 0.13, 2.0, 30);
  Model m{ModelKind::lfom, {}, {}};
  testing::set_parameters(m, {{"K", 1.3}, {"T", 1.1}, {"lambda", 0.55}, {"L", 3.37}});
  const auto delayed_input_response = simulate(m, d).y_dwe_mm;
  Model undelayed = m;
  undelayed.p.L = 0.0;
  auto y0 = simulate(undelayed, d).y_dwe_mm;
  for (double& v : y0) v -= d.y0_mm;
  std::vector<double> delayed_output;
  fractional_delay(y0, m.p.L / d.h, delayed_output);
  for (std::size_t k = 0; k < d.size(); ++k) {
    ASSERT_NEAR(delayed_input_response[k] - d.y0_mm, delayed_output[k], 1e-12) << k;
  }
}

// The integer-order models are the continuous ones sampled (exact zero-order hold, zoh.hpp):
// for a command stepping by A at t_s = k_s h and held, T ẏ + y = K u(t − L) gives exactly
// y(t) = y0 + K A (1 − e^{−(t − t_s − L)/T}) after t_s + L, at any h/T and any fractional L.
double fopdt_step(double t, double K, double A, double T, double L) {
  return t > L ? K * A * (1.0 - std::exp(-(t - L) / T)) : 0.0;
}

TEST(ExactHold, LiomIsTheContinuousStepResponseSampledAtAnyPeriod) {
  for (const double h : {0.125, 1.0}) {
    const std::size_t at = 7;
    const auto d = step_data(400, h, 5.0, at);
    Model m{ModelKind::liom, {}, {}};
    testing::set_parameters(m, {{"K", 0.6}, {"T", 2.3}, {"L", 3.37}});
    const auto y = simulate(m, d).y_dwe_mm;
    for (std::size_t k = 0; k < d.size(); ++k) {
      const double t = static_cast<double>(k) * h - static_cast<double>(at) * h;
      ASSERT_NEAR(y[k] - 40.0, fopdt_step(t, 0.6, 5.0, 2.3, 3.37), 1e-12) << "h " << h << " k " << k;
    }
  }
}

// Two lags in series, y(t) = K A (1 − (T e^{−τ/T} − T2 e^{−τ/T2})/(T − T2)), τ = t − t_s − L
// (T = T2: 1 − (1 + τ/T) e^{−τ/T}).
TEST(ExactHold, SopdIsTheContinuousStepResponseSampled) {
  const double h = 0.5, K = 1.7, A = 2.0, L = 1.3;
  const std::size_t at = 4;
  const auto d = step_data(200, h, A, at);
  for (const auto& [T, T2] : {std::pair{3.0, 0.8}, std::pair{2.0, 2.0}, std::pair{2.0, 2.0 + 1e-9}}) {
    Model m{ModelKind::sopd, {}, {}};
    testing::set_parameters(m, {{"K", K}, {"T", T}, {"T2", T2}, {"L", L}});
    const auto y = simulate(m, d).y_dwe_mm;
    for (std::size_t k = 0; k < d.size(); ++k) {
      const double tau = static_cast<double>(k) * h - static_cast<double>(at) * h - L;
      double expected = 0.0;
      if (tau > 0.0) {
        // (a difference of 1e-9 s is the repeated pole to 1e-9; the two-pole formula would lose
        // seven digits to cancellation there)
        expected = std::abs(T - T2) < 1e-6 ? 1.0 - (1.0 + tau / T) * std::exp(-tau / T)
                           : 1.0 - (T * std::exp(-tau / T) - T2 * std::exp(-tau / T2)) / (T - T2);
      }
      ASSERT_NEAR(y[k] - 40.0, K * A * expected, 1e-9) << "T " << T << " T2 " << T2 << " k " << k;
    }
  }
}

// The nesting LFOM ⊃ LIOM holds exactly: LFOM at λ = 1 is the integer model, not GL's backward
// Euler (which is h/2 slower and reads one sample early; GL is kept for λ ≠ 1).
TEST(ExactHold, LfomAtOrderOneIsLiom) {
  const auto d = step_data(500, 0.13, 2.0, 20);
  Model liom{ModelKind::liom, {}, {}};
  testing::set_parameters(liom, {{"K", 1.3}, {"T", 1.1}, {"L", 0.77}});
  Model lfom = liom;
  lfom.kind = ModelKind::lfom;
  lfom.p.lambda = 1.0;
  EXPECT_EQ(simulate(lfom, d).y_dwe_mm, simulate(liom, d).y_dwe_mm);
  // Near λ = 1 GL is close to it (no one-sample jump in the delay between the two schemes).
  lfom.p.lambda = 0.999;
  const auto gl = simulate(lfom, d).y_dwe_mm, zoh = simulate(liom, d).y_dwe_mm;
  for (std::size_t k = 0; k < d.size(); ++k) EXPECT_NEAR(gl[k], zoh[k], 0.05 * 2.6) << k;
}

// The fitter re-delays a cached LIOM response by blending two whole-sample delays with the
// ZOH weight (delay_interpolation_weight): exact, not an approximation.
TEST(ExactHold, AFractionalDelayIsABlendOfTwoWholeSampleDelays) {
  const auto d = step_data(300, 0.4, 2.0, 10);
  Model m{ModelKind::liom, {}, {}};
  testing::set_parameters(m, {{"K", 1.3}, {"T", 0.9}, {"L", 2.3}});
  const auto direct = simulate(m, d).y_dwe_mm;
  Model undelayed = m;
  undelayed.p.L = 0.0;
  auto g = simulate(undelayed, d).y_dwe_mm;
  for (double& v : g) v -= d.y0_mm;
  const double delay = m.p.L / d.h, frac = delay - std::floor(delay);
  std::vector<double> blended;
  blended_delay(g, delay, *delay_interpolation_weight(m, d.h, frac), blended);
  for (std::size_t k = 0; k < d.size(); ++k) ASSERT_NEAR(direct[k] - d.y0_mm, blended[k], 1e-12) << k;
  EXPECT_FALSE(delay_interpolation_weight(Model{ModelKind::sopd, {}, {}}, d.h, frac).has_value());
}

TEST(Sopd, IsTwoCascadedFirstOrderLagsWithUnitStaticGainTimesK) {
  const auto d = step_data(3000, 0.13, 1.0);
  Model sopd{ModelKind::sopd, {}, {}};
  testing::set_parameters(sopd, {{"K", 2.0}, {"T", 1.0}, {"T2", 0.5}});
  const auto y = simulate(sopd, d).y_dwe_mm;
  EXPECT_NEAR(y.back(), 42.0, 1e-9);
  // Slower start than a single lag: second-order response has zero initial slope.
  Model liom{ModelKind::liom, {}, {}};
  liom.p.K = 2.0;
  liom.p.T = 1.0;
  EXPECT_LT(simulate(sopd, d).y_dwe_mm[3], simulate(liom, d).y_dwe_mm[3]);
}

TEST(Lfom, ShortMemorySteadyStateCarriesTheTruncationBias) {
  const auto d = step_data(6000, 0.13, 1.0);
  Model m{ModelKind::lfom, {}, {}};
  testing::set_parameters(m, {{"K", 1.0}, {"T", 2.0}, {"lambda", 0.5}});
  const auto y = simulate(m, d).y_dwe_mm;
  EXPECT_NEAR(y.back() - 40.0, short_memory_steady_state(2.0, 0.5, 0.13, 500), 1e-9);
}

TEST(NonlinearFree, GainScalesWithUpstreamLevelOverHeadReferenceToTheGamma) {
  auto d = step_data(3000, 0.13, 1.0);
  d.y_up_mm.assign(d.size(), 66.0);
  Model m{ModelKind::nliom_f, {}, {}};
  testing::set_parameters(m, {{"K", 1.0}, {"T", 0.5}, {"gamma", 2.0}});
  m.p.head_ref_mm = 60.0;
  const auto y = simulate(m, d).y_dwe_mm;
  EXPECT_NEAR(y.back() - 40.0, std::pow(66.0 / 60.0, 2.0), 1e-9);
  EXPECT_NEAR(paper_gain(m), 1.0 / 3600.0, 1e-15);
}

TEST(NonlinearFree, WithGammaZeroEqualsTheLinearModel) {
  const auto d = step_data(1000, 0.13, 3.0, 10);
  Model nl{ModelKind::nlfom_f, {}, {}};
  testing::set_parameters(nl, {{"K", 0.8}, {"T", 1.3}, {"lambda", 0.6}, {"gamma", 0.0}, {"L", 1.0}});
  Model lin = nl;
  lin.kind = ModelKind::lfom;
  EXPECT_EQ(simulate(nl, d).y_dwe_mm, simulate(lin, d).y_dwe_mm);
}

TEST(NonlinearSubmerged, HeadUsesTheModelsOwnOutputSoTheStepSettlesWhereTheFlowLawBalances) {
  // Steady state of T D Δy + Δy = K ((y_up − y0 − Δy)/H)^γ Δu: Δy = K ((60 − 40 − Δy)/20)^γ Δu.
  const auto d = step_data(4000, 0.13, 4.0);
  Model m{ModelKind::nliom_s, {}, {}};
  testing::set_parameters(m, {{"K", 1.0}, {"T", 1.0}, {"gamma", 0.5}});
  m.p.head_ref_mm = 20.0;
  const double dy = simulate(m, d).y_dwe_mm.back() - 40.0;
  EXPECT_NEAR(dy, 1.0 * std::sqrt((20.0 - dy) / 20.0) * 4.0, 1e-6);
  EXPECT_LT(dy, 4.0);  // lower than the linear model's 4 mm: the head shrinks as y_dwe rises
}

TEST(NonlinearModels, RejectDataWithoutUpstreamLevelNamingTheFile) {
  auto d = step_data(100, 0.13, 1.0);
  d.y_up_mm.clear();
  d.source = "op1.csv";
  Model m{ModelKind::nlfom_s, {}, {}};
  try {
    simulate(m, d);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("op1.csv"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("y_up_mm"), std::string::npos);
  }
}

TEST(RateLimit, MovesTheGateAtConstantSpeedUntilItReachesTheCommand) {
  const std::vector<double> u{20, 25, 25, 25, 25, 15};
  const auto x = rate_limit(u, 0.5, 4.0);  // 2 mm per sample
  EXPECT_EQ(x, (std::vector<double>{20, 22, 24, 25, 25, 23}));
  EXPECT_EQ(rate_limit(u, 0.5, 0.0), u);
}

TEST(Quantisation, RoundsToTheNearestMultipleOfTheResolution) {
  EXPECT_DOUBLE_EQ(quantise(45.0312, 0.05), 45.05);
  EXPECT_DOUBLE_EQ(quantise(45.0249, 0.05), 45.0);
  EXPECT_DOUBLE_EQ(quantise(45.0249, 0.0), 45.0249);
  auto d = step_data(500, 0.13, 1.0);
  Model m{ModelKind::liom, {}, {0.0, 0.05}};
  for (double v : simulate(m, d).y_dwe_mm) EXPECT_NEAR(std::remainder(v, 0.05), 0.0, 1e-9);
}

TEST(FlowRegime, FollowsConditionsEightAndTen) {
  // y_lc = 0.81 y_dwe (y_dwe / x_up)^0.72 (eq. 23)
  EXPECT_NEAR(free_flow_limit_mm(45.0, 30.0), 0.81 * 45.0 * std::pow(1.5, 0.72), 1e-12);
  EXPECT_TRUE(is_free_flow(60.0, 45.0, 30.0));   // y_lc ≈ 48.8 < 60
  EXPECT_FALSE(is_free_flow(60.0, 45.0, 15.0));  // y_lc ≈ 80.4 > 60
}

TEST(Hybrid, SwitchesBetweenTheFreeAndSubmergedTermsByTheFlowCondition) {
  using testing::SyntheticSpec;
  SyntheticSpec s;
  s.u0 = 22.5;  // the regime boundary for y_up = 60, y_dwe = 45
  s.noise = 0.0;
  s.quantum = 0.0;
  Model m{ModelKind::hybrid, {}, {}};
  testing::set_parameters(m, {{"K", 0.8},
                                  {"T", 1.5},
                                  {"lambda", 0.6},
                                  {"gamma", 2.0},
                                  {"L", 2.0},
                                  {"K_sub", 1.5},
                                  {"gamma_sub", 0.5}});
  m.p.head_ref_mm = 60.0;
  m.p.head_ref_sub_mm = 15.0;
  const auto rec = testing::synthetic_recording(m, s);
  const auto d = prepare_data(rec);
  const auto r = simulate(m, d);
  std::size_t free = 0;
  for (int v : r.regime) free += static_cast<std::size_t>(v);
  EXPECT_GT(free, d.size() / 10);
  EXPECT_LT(free, d.size() * 9 / 10);
  // With both gains zero the output stays at the operating point.
  Model same = m;
  same.p.K_sub = 0.0;
  same.p.K = 0.0;
  const auto flat = simulate(same, d).y_dwe_mm;
  for (double v : flat) EXPECT_DOUBLE_EQ(v, d.y0_mm);
}

TEST(ModelValidation, NamesTheOffendingParameter) {
  Model m{ModelKind::lfom, {}, {}};
  m.p.lambda = -0.5;
  EXPECT_NE(validate(m).message().find("lambda"), std::string::npos);
  m.p.lambda = 0.5;
  m.p.L = -1.0;
  EXPECT_NE(validate(m).message().find("p.L"), std::string::npos);
  m.p.L = 0.0;
  m.actuation.quantum_mm = -0.05;
  EXPECT_NE(validate(m).message().find("quantum_mm"), std::string::npos);
}

}  // namespace
}  // namespace canalsim::reduced

namespace canalsim::reduced {
namespace {

// The mean reading of a quantising sensor, Σ_j q_j P(bin j), summed directly over the bins.
double direct_mean_reading(double mu, double r, double o, double sigma) {
  double mean = 0.0;
  const double centre = o + r * std::round((mu - o) / r);
  for (int j = -30; j <= 30; ++j) {
    const double q = centre + j * r;
    const double p = 0.5 * (std::erfc(-(q + 0.5 * r - mu) / (sigma * std::sqrt(2.0))) -
                            std::erfc(-(q - 0.5 * r - mu) / (sigma * std::sqrt(2.0))));
    mean += q * p;
  }
  return mean;
}

TEST(SensorReading, TheBiasSeriesIsTheMeanReadingSummedOverTheBins) {
  for (const double ratio : {0.08, 0.2, 0.3, 0.6}) {
    const ReadingBias bias{{0.1, 0.037}, ratio * 0.1};
    for (double mu = 44.9; mu < 45.1; mu += 0.0071) {
      double slope = 0.0;
      EXPECT_NEAR(mu + bias(mu, slope), direct_mean_reading(mu, 0.1, 0.037, ratio * 0.1), 1e-7) << ratio << " " << mu;
      double up = 0.0, down = 0.0;
      const double numeric = (bias(mu + 1e-6, up) - bias(mu - 1e-6, down)) / 2e-6;
      EXPECT_NEAR(slope, numeric, 1e-4);
    }
  }
}

TEST(SensorReading, TheLatticeOfQuantisedLevelsIsFoundAndContinuousLevelsHaveNone) {
  ExperimentData d;
  for (int k = 0; k < 500; ++k) d.y_dwe_mm.push_back(0.037 + 0.1 * std::round(450.0 + 30.0 * std::sin(0.01 * k)));
  const auto lattice = recorded_lattice({&d});
  EXPECT_NEAR(lattice.step, 0.1, 1e-9);
  EXPECT_NEAR(lattice.origin, 0.037, 1e-6);
  for (int k = 0; k < 500; ++k) d.y_dwe_mm[static_cast<std::size_t>(k)] = 45.0 + 3.0 * std::sin(0.0123 * k);
  EXPECT_EQ(recorded_lattice({&d}).step, 0.0);
}

}  // namespace
}  // namespace canalsim::reduced
