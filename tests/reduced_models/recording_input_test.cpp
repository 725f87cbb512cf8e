// Bad recordings as the reduced models see them: every problem is one line naming the file.
// (The reader itself is scenarios/recording.*; these tests pin what a fit's user gets.)
#include <gtest/gtest.h>

#include "reduced_models/data.hpp"
#include "core/recording.hpp"

namespace canalsim::reduced {
namespace {

std::string error_of(const std::string& text) {
  try {
    prepare_data(parse_recording(text, "bad.csv"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void expect_one_line_naming_file(const std::string& what, const std::string& fragment) {
  EXPECT_EQ(what.rfind("bad.csv", 0), 0u) << what;
  EXPECT_NE(what.find(fragment), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
}

TEST(BadRecording, NonIncreasingTimeIsRejected) {
  expect_one_line_naming_file(error_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.13,2,2\n0.13,1,2\n"),
                              "not increasing");
}

TEST(BadRecording, NonUniformTimeIsRejected) {
  expect_one_line_naming_file(error_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.13,2,2\n0.5,1,2\n"),
                              "not uniformly sampled");
}

TEST(BadRecording, NanIsRejected) {
  expect_one_line_naming_file(error_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.13,nan,2\n"), "u_mm");
}

TEST(BadRecording, MissingRequiredColumnIsRejected) {
  expect_one_line_naming_file(error_of("t_s,u_mm\n0,1\n0.13,2\n"), "y_dwe_mm");
}

TEST(BadRecording, ConstantInputIsRejectedAsHavingNoExcitation) {
  expect_one_line_naming_file(error_of("t_s,u_mm,y_dwe_mm\n0,5,2\n0.13,5,2\n0.26,5,2\n"),
                              "no excitation");
}

TEST(BadRecording, MissingUpstreamLevelIsReportedForNonlinearModels) {
  const auto d = prepare_data(parse_recording("t_s,u_mm,y_dwe_mm\n0,5,2\n0.13,6,2.1\n", "bad.csv"));
  try {
    require_upstream_level(d, "nliom-f");
    FAIL();
  } catch (const InputError& e) {
    expect_one_line_naming_file(e.what(), "y_up_mm");
  }
}

}  // namespace
}  // namespace canalsim::reduced
