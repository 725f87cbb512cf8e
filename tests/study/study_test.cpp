// Tests of reduced_models/study.*: the embedded paper tables, the generated conclusions, and the
// table builder on synthetic recordings of a known model.
#include "study/paper.hpp"
#include "study/study.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "testing/synthetic.hpp"

namespace canalsim::study {
namespace {

TEST(PaperTables, ReturnThePublishedNumbers) {
  // Spot checks against ../shared/reference/paper_tables.json (the paper's Tables 1, 4, 5, 7, 8).
  EXPECT_DOUBLE_EQ(paper_value("/table1_LIOM/fits/op1/K"), 0.6806);
  EXPECT_DOUBLE_EQ(paper_value("/table1_LIOM/fits/op1/nrmse"), 70.95);
  EXPECT_DOUBLE_EQ(paper_value("/table1_LIOM/uncertainty_pct/T"), 43.19);
  EXPECT_DOUBLE_EQ(paper_value("/table4_NLFOM_S/fits/op2/lambda"), 0.48);
  EXPECT_DOUBLE_EQ(paper_value("/table5_validation_submerged/op2*/NLFOM-S"), 78.38);
  EXPECT_DOUBLE_EQ(paper_value("/table7_NLFOM_F/nominal/gamma"), 5.65);
  EXPECT_DOUBLE_EQ(paper_value("/table8_validation_free/op4*/LIOM"), 70.21);
  EXPECT_DOUBLE_EQ(paper_value("/experiment/prbs/clock_period_s"), 0.5);
}

TEST(PaperTables, NameTheMissingEntry) {
  try {
    paper_value("/table1_LIOM/fits/op9/K");
    FAIL() << "expected std::out_of_range";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("/table1_LIOM/fits/op9/K"), std::string::npos);
  }
}

TEST(Claims, ADifferenceClaimHoldsWhenEveryDifferenceIsPositive) {
  const auto c = difference_claim("table4", "NLFOM-S beats NLIOM-S", {"op1", "op2"}, {3.13, 5.91}, {2.1, 0.4});
  EXPECT_TRUE(c.holds);
  EXPECT_EQ(c.table, "table4");
  EXPECT_EQ(c.text, "NLFOM-S beats NLIOM-S at op1 and op2: paper +3.13 and +5.91 points, here +2.10 and "
                    "+0.40 points — holds.");
}

TEST(Claims, ADifferenceClaimDoesNotHoldAndNamesWhereItFails) {
  const auto c = difference_claim("table4", "NLFOM-S beats NLIOM-S", {"op1", "op2"}, {3.13, 5.91}, {2.1, -0.4});
  EXPECT_FALSE(c.holds);
  EXPECT_NE(c.text.find("here +2.10 and -0.40 points — does not hold (op2)."), std::string::npos) << c.text;
  const auto all = difference_claim("t", "A beats B", {"op1", "op2"}, {1.0, 1.0}, {-1.0, 0.0});
  EXPECT_FALSE(all.holds);
  EXPECT_NE(all.text.find("— does not hold."), std::string::npos) << all.text;
}

TEST(Claims, ATieAtThePrintedPrecisionIsNotAWin) {
  const auto c = difference_claim("table3", "NLIOM-S beats LIOM", {"op1"}, {10.26}, {0.001});
  EXPECT_FALSE(c.holds);
  EXPECT_NE(c.text.find("here +0.00 points — does not hold."), std::string::npos) << c.text;
}

TEST(Claims, ARangeClaimChecksEveryValue) {
  EXPECT_TRUE(range_claim("table6", "γ is large", "γ ≥ 3", {"op3", "op4"}, {6.15, 6.85}, {4.0, 3.0}, 3.0, 1e9).holds);
  const auto c = range_claim("table6", "γ is large", "γ ≥ 3", {"op3", "op4"}, {6.15, 6.85}, {1.2, 5.0}, 3.0, 1e9);
  EXPECT_FALSE(c.holds);
  EXPECT_NE(c.text.find("does not hold (op3)"), std::string::npos) << c.text;
}

TEST(Claims, ASameClaimComparesNames) {
  EXPECT_TRUE(same_claim("table5", "Best model at op1*", "NLFOM-S", "NLFOM-S").holds);
  const auto c = same_claim("table5", "Best model at op1*", "NLFOM-S", "LFOM");
  EXPECT_FALSE(c.holds);
  EXPECT_EQ(c.text, "Best model at op1*: paper NLFOM-S, here LFOM — does not hold.");
}

TEST(Claims, RejectMismatchedSizes) {
  EXPECT_THROW(difference_claim("t", "x", {"op1"}, {1.0, 2.0}, {1.0}), std::invalid_argument);
}

TEST(StudyData, TakesTheOperatingPointFromTheMetadata) {
  Recording rec;
  rec.source = "op1.csv";
  rec.set_meta("operating_opening_mm", "15");
  rec.set_column("t_s", {0.0, 0.13, 0.26, 0.39});
  rec.set_column("u_mm", {20.0, 20.0, 10.0, 20.0});
  rec.set_column("y_dwe_mm", {40.0, 40.0, 40.0, 40.5});
  const auto d = study_data(rec);
  EXPECT_DOUBLE_EQ(d.u0_mm, 15.0);
  rec.set_meta("operating_opening_mm", "fifteen");
  EXPECT_THROW(study_data(rec), InputError);
}

// Two 60 s synthetic recordings of one known LFOM at two operating points.
TEST(ModelTable, RecoversTheParametersOfAKnownLfom) {
  Model truth;
  truth.kind = ModelKind::lfom;
  testing::set_parameters(truth, {{"K", 0.8}, {"T", 1.3}, {"lambda", 0.6}});
  truth.p.L = 4.94;  // 38 samples of 0.13 s
  std::map<std::string, ExperimentData> data;
  for (const auto& [name, u0] : {std::pair{"op1", 15.0}, std::pair{"op2", 25.0}}) {
    testing::SyntheticSpec spec;
    spec.n = 462;  // 60 s
    spec.u0 = u0;
    spec.noise = 0.01;
    spec.seed = static_cast<unsigned>(u0);
    auto rec = testing::synthetic_recording(truth, spec);
    rec.set_meta("operating_opening_mm", std::to_string(u0));
    data[name] = study_data(rec);
  }
  StudyOptions options;
  const auto table = build_model_table({"table2", "table2_LFOM", "LFOM", ModelKind::lfom, {"op1", "op2"}}, data, options);
  ASSERT_EQ(table.fits.size(), 2u);
  for (const auto* m : {&table.fits[0].model, &table.fits[1].model, &table.nominal.model}) {
    EXPECT_NEAR(m->p.K, truth.p.K, 0.05 * truth.p.K);
    EXPECT_NEAR(m->p.T, truth.p.T, 0.05 * truth.p.T);
    EXPECT_NEAR(m->p.lambda, truth.p.lambda, 0.03);
    EXPECT_NEAR(m->p.L, truth.p.L, 0.13);
  }
  EXPECT_GT(table.fits[0].nrmse.front(), 90.0);
  // Same truth at both points: the uncertainty indices are small.
  EXPECT_LT(table.uncertainty.at("K"), 0.05);
  EXPECT_LT(table.uncertainty.at("lambda"), 0.05);
}

}  // namespace
}  // namespace canalsim::study
