// Why a conclusion does not hold (study/explanations.*): the causes carry the study's own figures,
// computed from the result they explain, and name the figure that shows them; a conclusion that
// holds carries none.
#include "study/explanations.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace canalsim::study {
namespace {

ModelTable table(ModelKind kind, std::vector<std::string> experiments, const std::vector<double>& gains) {
  ModelTable t;
  t.spec.kind = kind;
  t.spec.experiments = std::move(experiments);
  for (double K : gains) {
    FitResult f;
    f.model.kind = kind;
    f.model.p.K = K;
    f.model.p.T = 0.2;
    f.model.p.lambda = 1.0;
    t.fits.push_back(f);
  }
  return t;
}

GammaSweep sweep(std::vector<double> nrmse) {
  GammaSweep s;
  for (std::size_t i = 0; i < nrmse.size(); ++i) s.gamma.push_back(0.5 * static_cast<double>(i));
  s.nrmse = std::move(nrmse);
  return s;
}

// The simulated canal's shape of result: small free-flow gains, a free-flow sweep that hardly
// moves (and diverges at its end), a submerged sweep best at γ = 0 at op1.
StudyResult simulated_canal_result() {
  constexpr double kDiverged = std::numeric_limits<double>::quiet_NaN();
  StudyResult r;
  r.tables.push_back(table(ModelKind::liom, {"op1", "op2", "op3", "op4"}, {0.49, 0.47, 0.12, 0.06}));
  r.tables.push_back(table(ModelKind::lfom, {"op1", "op2", "op3", "op4"}, {0.49, 0.47, 0.12, 0.06}));
  ModelTable submerged = table(ModelKind::nliom_s, {"op1", "op2"}, {0.49, 0.47});
  submerged.sweeps = {sweep({74.8, 72.0, 68.5, kDiverged}), sweep({78.2, 80.4, 78.5, kDiverged})};
  submerged.sweeps[0].best = 0;
  submerged.sweeps[1].best = 1;
  r.tables.push_back(submerged);
  ModelTable free = table(ModelKind::nliom_f, {"op3", "op4"}, {0.12, 0.06});
  free.sweeps = {sweep({12.69, 12.70, 12.77, kDiverged}), sweep({19.96, 19.95, 19.97, 19.96})};
  r.tables.push_back(free);
  r.spectrum.bandwidth_design_rad_s = 5.57;
  r.spectrum.bandwidth_measured_rad_s = 5.16;
  return r;
}

Claim failing(const std::string& table, const std::string& text) { return {table, text, false, ""}; }

TEST(Explanations, AConclusionThatHoldsHasNoCause) {
  EXPECT_EQ(why_it_fails({"table1", "The LIOM delay L agrees with the paper's within 1 s …", true, ""}, simulated_canal_result()), "");
}

TEST(Explanations, TheFreeFlowGainsAreQuotedFromTheFreeFlowExperimentsFits) {
  const std::string why =
      why_it_fails(failing("table7", "The free-flow gains (LIOM K at op3, op4) agree with the paper's within 30 % …"),
                   simulated_canal_result());
  EXPECT_NE(why.find("0.12 and 0.06 mm/mm"), std::string::npos) << why;
  EXPECT_EQ(why.find("0.49"), std::string::npos) << why;  // op1's gain is not a free-flow one
  EXPECT_NE(why.find("bode.html"), std::string::npos) << why;
}

TEST(Explanations, TheFreeFlowExponentIsUndeterminedByTheWidestChangeOfItsSweeps) {
  // Largest change over γ: 12.77 − 12.69 = 0.08 at op3 (the diverged γ left out), 0.02 at op4.
  const std::string why = why_it_fails(failing("table6", "The free-flow exponent is large (γ ≥ 3) …"), simulated_canal_result());
  EXPECT_NE(why.find("at most 0.08 points"), std::string::npos) << why;
  EXPECT_NE(why.find("Figure 10"), std::string::npos) << why;
}

TEST(Explanations, TheSubmergedExponentNamesWhereEachSweepIsBest) {
  const std::string why =
      why_it_fails(failing("table3", "The NLIOM-S exponent is near the orifice law's 1/2 …"), simulated_canal_result());
  EXPECT_NE(why.find("γ = 0 at op1 (Nrmse 74.8 %)"), std::string::npos) << why;
  EXPECT_NE(why.find("γ = 0.5 at op2 (Nrmse 80.4 %)"), std::string::npos) << why;
  EXPECT_NE(why.find("Figure 8"), std::string::npos) << why;
}

TEST(Explanations, EveryConclusionTheSimulatedCanalFailsHasACauseAndItsFigure) {
  const StudyResult r = simulated_canal_result();
  const std::vector<Claim> claims{
      failing("table1", "The LIOM gain K agrees with the paper's within 30 % …"),
      failing("table1", "The LIOM fit quality Nrmse agrees with the paper's within 10 points …"),
      failing("table1", "The LIOM time constant varies more than its gain across op1–op4 …"),
      failing("table2", "LFOM beats LIOM (Nrmse) …"),
      failing("table2", "The LFOM order is clearly fractional …"),
      failing("table4", "NLFOM-S beats NLIOM-S (Nrmse) …"),
      failing("table4", "NLFOM-S beats LFOM (Nrmse) …"),
      failing("table5", "Best nominal model in validation at op1* …"),
      failing("table6", "NLIOM-F beats LIOM (Nrmse) …"),
      failing("table7", "NLFOM-F beats NLIOM-F (Nrmse) …"),
      failing("table8", "Best nominal model in validation at op3b …"),
      failing("figure6", "The submerged-flow experiments stay submerged …"),
      failing("figure4", "The PRBS −3 dB bandwidth agrees with the paper's 5.58 rad/s within 5 % …")};
  for (const Claim& c : claims) {
    const std::string why = why_it_fails(c, r);
    EXPECT_FALSE(why.empty()) << c.text;
    const bool names_its_evidence = why.find("Figure") != std::string::npos || why.find("bode.html") != std::string::npos ||
                                    why.find("Table") != std::string::npos || why.find("docs/") != std::string::npos;
    EXPECT_TRUE(names_its_evidence) << c.text << ": " << why;
  }
  EXPECT_NE(why_it_fails(claims.back(), r).find("5.16 rad/s against the ideal clock's 5.57"), std::string::npos);
}

}  // namespace
}  // namespace canalsim::study
