// Mismatch location: the model-error band lies where an input filter leaks into the residual;
// windows sit where the residual is large; groups split by regime and level.
#include "diagnosis/locate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "testing/signals.hpp"

namespace canalsim::diagnosis {
namespace {

using testing::white_noise;

TEST(ModelErrorBand, LowPassLeakIsFoundAtLowFrequencies) {
  const double h = 0.13;
  const auto u = white_noise(4000, 1);
  auto e = white_noise(4000, 2, 0.1);
  // e += first-order low-pass of u (pole 0.95): gain falls with frequency.
  double state = 0.0;
  for (std::size_t t = 0; t < u.size(); ++t) {
    state = 0.95 * state + 0.05 * u[t];
    e[t] += state;
  }
  const FrequencyBand b = model_error_band({u}, {e}, h);
  ASSERT_TRUE(b.found);
  EXPECT_LT(b.low_hz, 0.05);
  EXPECT_GT(b.high_hz, b.low_hz);
  EXPECT_LT(b.high_hz, 0.5 / h);
}

TEST(ModelErrorBand, IndependentResidualLeavesNoWideBand) {
  const auto u = white_noise(4000, 3), e = white_noise(4000, 4);
  const FrequencyBand b = model_error_band({u}, {e}, 0.13);
  // At the 99% level a few isolated grid points may poke out; never a wide band.
  if (b.found) {
    EXPECT_LT(b.high_hz - b.low_hz, 0.3);
  }
}

RecordingResiduals synthetic(std::size_t n) {
  RecordingResiduals r;
  r.name = "synthetic";
  r.period_s = 0.1;
  r.primary = "y_dwe_mm";
  for (std::size_t k = 0; k < n; ++k) {
    r.t.push_back(0.1 * static_cast<double>(k));
    r.u.push_back((k / 50) % 2 ? 20.0 : 10.0);
    r.level.push_back(40.0 + std::sin(0.02 * static_cast<double>(k)));
    r.regime.push_back(k < n / 2 ? 0.0 : 1.0);  // free, then submerged
  }
  r.residuals["y_dwe_mm"] = white_noise(n, 5, 0.05);
  return r;
}

TEST(Locate, WindowIsWhereTheResidualIsLarge) {
  RecordingResiduals r = synthetic(2000);
  for (std::size_t k = 1200; k < 1300; ++k) r.residuals["y_dwe_mm"][k] += 1.0;  // t = 120..130 s
  const Mismatch m = locate({r});
  ASSERT_FALSE(m.windows.empty());
  EXPECT_NEAR(m.windows.front().start_s, 120.0, 2.0);
  EXPECT_NEAR(m.windows.front().end_s, 130.0, 2.0);
  EXPECT_EQ(m.windows.front().recording, "synthetic");
  // The bump lies in the submerged half.
  ASSERT_EQ(m.by_regime.size(), 2u);
  EXPECT_EQ(m.by_regime[1].name, "submerged");
  EXPECT_GT(m.by_regime[1].rms, 3.0 * m.by_regime[0].rms);
  ASSERT_EQ(m.by_recording.size(), 1u);
  EXPECT_NEAR(m.by_recording[0].free_fraction, 0.5, 1e-12);
  EXPECT_FALSE(m.by_recording[0].white);
}

TEST(Locate, InconsistentLengthsAreRejected) {
  RecordingResiduals r = synthetic(100);
  r.u.pop_back();
  EXPECT_THROW(locate({r}), std::invalid_argument);
  LocateOptions o;
  o.fir_order = 1;
  EXPECT_NE(o.validate().message().find("fir_order"), std::string::npos);
}

}  // namespace
}  // namespace canalsim::diagnosis
