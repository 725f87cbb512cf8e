// PRBS (scenarios/prbs.*): maximal-length LFSR sequences and the design figures of the paper's
// Section 4.3.
#include "scenarios/prbs.hpp"

#include <cmath>
#include <complex>
#include <cstdint>
#include <gtest/gtest.h>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "testing/refusals.hpp"

namespace canalsim {
namespace {

std::vector<int> plus_minus(const std::vector<std::uint8_t>& bits) {
  std::vector<int> s(bits.size());
  for (std::size_t i = 0; i < bits.size(); ++i) s[i] = bits[i] ? 1 : -1;
  return s;
}

TEST(Lfsr, EveryTapSetHasTheMaximalPeriod) {
  // The register visits all 2^n - 1 non-zero states before it first returns to its start.
  for (int n = prbs_min_stages; n <= prbs_max_stages; ++n) {
    const std::uint32_t start = initial_register_from_seed(n, 7);
    Lfsr lfsr(n, start);
    std::uint64_t steps = 0;
    do {
      lfsr.next();
      ++steps;
    } while (lfsr.state() != start && steps <= (std::uint64_t{1} << n));
    EXPECT_EQ(steps, (std::uint64_t{1} << n) - 1) << n << " stages";
  }
}

TEST(Lfsr, NineStagesGive511Bits) {
  EXPECT_EQ(maximal_length_sequence(9, 1).size(), 511u);
  EXPECT_EQ(maximal_length_taps(9), (std::vector<int>{9, 5}));
}

TEST(Lfsr, RejectsStagesOutside2To20AndAZeroRegister) {
  EXPECT_THROW(maximal_length_taps(1), std::invalid_argument);
  EXPECT_THROW(maximal_length_taps(21), std::invalid_argument);
  EXPECT_THROW(Lfsr(9, 0), std::invalid_argument);
  EXPECT_THROW(Lfsr(9, 512), std::invalid_argument);
}

TEST(MaximalLengthSequence, HasOneMoreOneThanZero) {
  for (int n = prbs_min_stages; n <= prbs_max_stages; ++n) {
    const auto bits = maximal_length_sequence(n, 3);
    const auto ones = std::accumulate(bits.begin(), bits.end(), std::size_t{0});
    EXPECT_EQ(ones, std::size_t{1} << (n - 1)) << n;
    EXPECT_EQ(bits.size() - ones, (std::size_t{1} << (n - 1)) - 1) << n;
  }
}

TEST(MaximalLengthSequence, PeriodicAutocorrelationIsTwoValued) {
  // R(0) = N, R(k) = -1 for 0 < k < N, in +-1 form.
  for (int n = prbs_min_stages; n <= 12; ++n) {
    const auto s = plus_minus(maximal_length_sequence(n, 11));
    const std::size_t N = s.size();
    for (std::size_t lag = 0; lag < N; ++lag) {
      long r = 0;
      for (std::size_t i = 0; i < N; ++i) r += s[i] * s[(i + lag) % N];
      ASSERT_EQ(r, lag == 0 ? static_cast<long>(N) : -1L) << n << " stages, lag " << lag;
    }
  }
}

TEST(MaximalLengthSequence, DiscreteSpectrumIsFlatApartFromTheMean) {
  // The DFT of the autocorrelation above: |X_0|^2 = 1, |X_m|^2 = N + 1 for 0 < m < N; the PRBS
  // is white over its N - 1 lines, the reason to use it (Section 4.3).
  const auto s = plus_minus(maximal_length_sequence(9, 1));
  const std::size_t N = s.size();
  for (std::size_t m = 0; m < N; m += 7) {
    std::complex<double> X = 0.0;
    for (std::size_t i = 0; i < N; ++i) {
      X += static_cast<double>(s[i]) * std::polar(1.0, -2.0 * std::numbers::pi * double(m * i) / double(N));
    }
    EXPECT_NEAR(std::norm(X), m == 0 ? 1.0 : double(N + 1), 1e-6) << m;
  }
}

TEST(MaximalLengthSequence, AnotherSeedGivesADifferentShiftOfTheSameSequence) {
  const auto a = maximal_length_sequence(9, 1);
  const auto b = maximal_length_sequence(9, 2);
  EXPECT_NE(a, b);
  bool is_shift = false;
  for (std::size_t k = 0; k < a.size() && !is_shift; ++k) {
    is_shift = std::equal(a.begin(), a.end(), b.begin() + 0, [&, i = std::size_t{0}](auto x, auto) mutable {
      return x == b[(i++ + k) % b.size()];
    });
  }
  EXPECT_TRUE(is_shift);
  EXPECT_EQ(maximal_length_sequence(9, 1), a);  // reproducible
}

TEST(PrbsDesign, ReproducesThePaperSection4_3) {
  const PrbsDesign d = design_prbs(9, 0.5);
  EXPECT_EQ(d.length, 511u);
  EXPECT_DOUBLE_EQ(d.period, 255.5);  // the paper prints 2555 s: 511 x 0.5 = 255.5
  EXPECT_DOUBLE_EQ(d.first_null, 2.0);
  EXPECT_DOUBLE_EQ(d.clock_frequency, 2.0);
  EXPECT_NEAR(d.lowest_frequency, 1.0 / 255.5, 1e-15);
  // -3 dB of the sinc^2 envelope at 0.4429 / Tc; the paper reads 5.58 rad/s off its Figure 4.
  EXPECT_NEAR(d.bandwidth_3db, 0.88589, 1e-5);
  EXPECT_NEAR(2 * std::numbers::pi * d.bandwidth_3db, 5.58, 0.02);
  // Rule (18): f_c = 2.5 f_max, with the paper's f_max = 0.88 Hz, f_c ~ 2 Hz.
  EXPECT_NEAR(d.max_frequency_of_interest, 0.8, 1e-12);
}

TEST(PrbsDesign, HalfPowerPointOfSincSquaredIsComputed) {
  const double x = sinc_squared_half_power_point();
  const double s = std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
  EXPECT_NEAR(s * s, 0.5, 1e-14);
  EXPECT_NEAR(x, 0.442946, 1e-6);
}

TEST(PrbsSignal, SwitchesBetweenOperatingPointPlusAndMinusAmplitudeEveryClock) {
  PrbsOptions options;
  options.operating_point = 0.025;
  options.start_time = 10.0;
  const PrbsSignal u(options);
  EXPECT_EQ(u.value(0.0), 0.025);
  const auto& bits = u.bits();
  for (std::size_t k = 0; k < 1100; ++k) {
    const double t = 10.0 + 0.5 * static_cast<double>(k);
    const double expected = 0.025 + (bits[k % 511] ? 0.005 : -0.005);
    EXPECT_EQ(u.value(t), expected) << k;
    EXPECT_EQ(u.value(t + 0.49), expected) << k;
  }
}

TEST(PrbsSignal, SampleTimesOnAClockEdgeTakeTheNewBit) {
  // 50 x 0.13 s = 6.5 s = 13 clocks, up to round-off in the product.
  PrbsOptions options;
  const PrbsSignal u(options);
  EXPECT_EQ(u.value(50 * 0.13), u.value(6.5 + 0.1));
}

// The jumps are the clock edges where the level changes, found here by sampling each clock
// period's middle: the first edge (from the operating point) included, edges without a change,
// and `from` itself, excluded.
TEST(PrbsSignal, JumpsAreTheClockEdgesWhereTheBitChanges) {
  PrbsOptions options;
  options.operating_point = 0.025;
  options.start_time = 2.0;
  const PrbsSignal u(options);
  std::vector<double> expected;
  double before = u.value(1.0);
  for (int k = 0; 2.0 + 0.5 * k <= 60.0; ++k) {
    const double edge = 2.0 + 0.5 * k, level = u.value(edge + 0.25);
    if (level != before) expected.push_back(edge);
    before = level;
  }
  ASSERT_GT(expected.size(), 40u);  // half the 116 edges change on average
  EXPECT_LT(expected.size(), 116u);
  EXPECT_EQ(u.jumps(0.0, 60.0), expected);
  const std::vector<double> later = u.jumps(expected[3], 60.0);
  EXPECT_EQ(later, std::vector<double>(expected.begin() + 4, expected.end()));
}

TEST(PrbsOptions, ValidationNamesTheField) {
  using testing::validation_message;
  EXPECT_TRUE(PrbsOptions{}.validate());
  EXPECT_EQ(validation_message<PrbsOptions>([](auto& o) { o.stages = 21; }), "stages = 21: expected an integer in [2, 20]");
  EXPECT_EQ(validation_message<PrbsOptions>([](auto& o) { o.clock_period = 0.0; }),
            "clock_period = 0: expected a value in (0, 3600] s");
  PrbsOptions options;
  options.clock_period = 0.0;
  EXPECT_THROW(PrbsSignal{options}, std::invalid_argument);
}

}  // namespace
}  // namespace canalsim
