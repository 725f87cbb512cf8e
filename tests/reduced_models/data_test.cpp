// Tests of reduced_models/data.*: preparing recordings for the models (operating point,
// upstream level, excitation check).
#include "reduced_models/data.hpp"

#include <gtest/gtest.h>

#include <string>

#include "testing/recordings.hpp"
#include "testing/refusals.hpp"

namespace canalsim::reduced {
namespace {

Recording recording(const std::vector<double>& u, const std::vector<double>& y,
                    bool with_y_up = true) {
  Recording r;
  r.source = "op1.csv";
  std::vector<double> t;
  for (std::size_t k = 0; k < u.size(); ++k) t.push_back(0.13 * static_cast<double>(k));
  r.set_column("t_s", t);
  r.set_column("u_mm", u);
  r.set_column("y_dwe_mm", y);
  if (with_y_up) r.set_column("y_up_mm", std::vector<double>(u.size(), 61.0));
  return r;
}

TEST(PrepareData, TakesTheOperatingPointFromTheSamplesBeforeTheInputFirstMoves) {
  const auto d = prepare_data(recording({15, 15, 15, 20, 10}, {40.0, 40.1, 39.9, 40.0, 42.0}));
  EXPECT_DOUBLE_EQ(d.u0_mm, 15.0);
  EXPECT_NEAR(d.y0_mm, 40.0, 1e-12);
  EXPECT_NEAR(d.h, 0.13, 1e-12);
  EXPECT_TRUE(d.has_upstream_level());
  EXPECT_EQ(d.source, "op1.csv");
}

TEST(PrepareData, UsesAGivenOperatingPoint) {
  DataOptions o;
  o.u0_mm = 12.0;
  o.y0_mm = 39.0;
  const auto d = prepare_data(recording({15, 20, 10}, {40, 41, 42}), o);
  EXPECT_DOUBLE_EQ(d.u0_mm, 12.0);
  EXPECT_DOUBLE_EQ(d.y0_mm, 39.0);
}

// A simulated experiment settles at the operating point and then starts its PRBS, possibly on
// the +5 mm bit: the metadata, not the first command, is the point the canal rested at. A value
// that is not an opening is an error naming the key, never silently replaced by the first command
// (which changes the fit).
TEST(PrepareData, TakesTheOperatingPointFromTheRecordingsMetadata) {
  Recording r = recording({20, 20, 10, 20}, {40, 40, 40, 41});
  EXPECT_DOUBLE_EQ(prepare_data(r).u0_mm, 20.0);
  r.set_meta("operating_opening_mm", "15");
  EXPECT_DOUBLE_EQ(prepare_data(r).u0_mm, 15.0);
  for (const char* bad : {"not a number", "nan", "1e300", "-5", "15 mm"}) {
    r.set_meta("operating_opening_mm", bad);
    try {
      (void)prepare_data(r);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("metadata operating_opening_mm: '" + std::string(bad) + "': expected"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(PrepareData, FillsAConstantUpstreamLevelOnlyWhenTheColumnIsAbsent) {
  DataOptions o;
  o.upstream_level_mm = 60.0;
  const auto without = prepare_data(recording({15, 20, 10}, {40, 41, 42}, false), o);
  EXPECT_TRUE(without.y_up_is_constant_option);
  EXPECT_EQ(without.y_up_mm, std::vector<double>(3, 60.0));
  const auto with = prepare_data(recording({15, 20, 10}, {40, 41, 42}, true), o);
  EXPECT_EQ(with.y_up_mm, std::vector<double>(3, 61.0));
  EXPECT_FALSE(prepare_data(recording({15, 20, 10}, {40, 41, 42}, false)).has_upstream_level());
}

TEST(PrepareData, RejectsAnInputWithoutExcitationNamingTheFile) {
  try {
    prepare_data(recording({15, 15, 15}, {40, 41, 42}));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("op1.csv: u_mm is constant", 0), 0u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

TEST(PrepareData, RejectsInvalidOptionsNamingTheField) {
  DataOptions o;
  o.upstream_level_mm = -3.0;
  EXPECT_NE(o.validate().message().find("upstream_level_mm"), std::string::npos);
  EXPECT_THROW(prepare_data(recording({15, 20}, {40, 41}), o), InputError);
}

TEST(RequireUpstreamLevel, NamesTheFileTheModelAndTheWayOut) {
  const auto d = prepare_data(recording({15, 20, 10}, {40, 41, 42}, false));
  try {
    require_upstream_level(d, "nlfom-s");
    FAIL();
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("op1.csv"), std::string::npos);
    EXPECT_NE(what.find("nlfom-s"), std::string::npos);
    EXPECT_NE(what.find("--upstream-level"), std::string::npos);
  }
}

// Declared units: a command in encoder counts (0.13 mm each) and levels in cm become mm inside,
// and a gain in mm/mm converts to cm/counts by u_scale / y_scale.
TEST(DeclaredUnits, CountsAndCentimetresAreConvertedToMillimetres) {
  Recording rec;
  rec.source = "counts.csv";
  rec.set_meta("u_unit", "counts");
  rec.set_meta("u_scale_mm_per_unit", "0.13");
  rec.set_meta("y_unit", "cm");
  rec.set_meta("y_scale_mm_per_unit", "10");
  rec.set_column("t_s", {0.0, 0.1, 0.2, 0.3});
  rec.set_column("u_mm", {100.0, 100.0, 150.0, 150.0});
  rec.set_column("y_up_mm", {6.0, 6.0, 6.0, 6.0});
  rec.set_column("y_dwe_mm", {4.5, 4.5, 4.6, 4.7});
  const auto d = prepare_data(rec);
  EXPECT_DOUBLE_EQ(d.u_mm[2], 19.5);
  EXPECT_DOUBLE_EQ(d.u0_mm, 13.0);
  EXPECT_DOUBLE_EQ(d.y_dwe_mm[3], 47.0);
  EXPECT_DOUBLE_EQ(d.y_up_mm[0], 60.0);
  EXPECT_DOUBLE_EQ(d.y0_mm, 45.0);
  EXPECT_DOUBLE_EQ(declared_gain_factor(d), 0.013);  // 1 mm/mm = 0.013 cm/count
  EXPECT_EQ(declared_gain_unit(d), "cm/counts");
}

// prepare_data refuses `rec` with one InputError that says `expected`.
void expect_refused(const Recording& rec, const std::string& expected) {
  EXPECT_TRUE(testing::refuses_input([&] { (void)prepare_data(rec); }, expected));
}

TEST(DeclaredUnits, AUnitWithoutAScaleOrABadScaleIsAnErrorNamingTheKey) {
  Recording rec = testing::command_and_level("counts.csv", {0.0, 0.1, 0.2}, {100.0, 150.0, 150.0}, {45.0, 45.0, 46.0});
  rec.set_meta("u_unit", "counts");
  expect_refused(rec, "counts.csv: metadata u_unit: counts needs u_scale_mm_per_unit");
  rec.set_meta("u_scale_mm_per_unit", "-1");
  expect_refused(rec, "u_scale_mm_per_unit: '-1': expected a number of mm per unit in [1e-06, 1000000]");
}

}  // namespace
}  // namespace canalsim::reduced
