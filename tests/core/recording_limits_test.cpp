// Numbers a recording may hold (docs/recording-format.md): finite, at most 1e12 in magnitude,
// sampled at 1 µs or slower; metadata always one line per key, so canalsim reads its own files.
#include <gtest/gtest.h>

#include <string>

#include "core/errors.hpp"
#include "core/recording.hpp"

namespace {

using canalsim::InputError;
using canalsim::parse_recording;

std::string rows(const std::string& middle_y) {
  return "t_s,u_mm,y_dwe_mm\n0,1,50\n0.1,1," + middle_y + "\n0.2,1,50\n";
}

void expect_refused(const std::string& text, const std::string& part) {
  try {
    (void)parse_recording(text, "r.csv");
    FAIL() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(RecordingLimits, HugeValuesAreRefusedNamingFileAndLine) {
  expect_refused(rows("1e308"), "r.csv:3: column y_dwe_mm: value 1e+308 is out of range");
  expect_refused(rows("-1e300"), "r.csv:3: column y_dwe_mm");
  expect_refused(rows("1.0000001e12"), "r.csv:3");
  EXPECT_NO_THROW((void)parse_recording(rows("1e12"), "r.csv"));
  EXPECT_NO_THROW((void)parse_recording(rows("-1e12"), "r.csv"));
}

TEST(RecordingLimits, ASampleStepBelowAMicrosecondIsRefused) {
  expect_refused("t_s,u_mm,y_dwe_mm\n0,1,50\n1e-12,1,50\n2e-12,1,50\n", "r.csv:3: t_s steps by 1e-12 s");
  EXPECT_NO_THROW((void)parse_recording("t_s,u_mm,y_dwe_mm\n0,1,50\n1e-6,1,50\n2e-6,1,50\n", "r.csv"));
}

TEST(RecordingLimits, AHugeFieldIsNotEchoedWhole) {
  try {
    (void)parse_recording(rows(std::string(1 << 20, 'x')), "r.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_LT(std::string(e.what()).size(), 300u);
    EXPECT_NE(std::string(e.what()).find("(1048576 characters)"), std::string::npos);
  }
}

// A scenario named "a\nb" must not write "# scenario: a" and a line "b" that the reader would take
// for the header.
TEST(RecordingLimits, LineBreaksInMetadataAreWrittenAsSpaces) {
  canalsim::Recording rec = parse_recording(rows("51"), "r.csv");
  rec.set_meta("scenario", "two\nlines\r\nhere");
  rec.set_meta("experiment", "op1");
  const canalsim::Recording back = parse_recording(canalsim::format_recording(rec), "back.csv");
  EXPECT_EQ(back.meta("scenario"), "two lines  here");
  EXPECT_EQ(back.meta("experiment"), "op1");
  EXPECT_EQ(back.size(), 3u);
}

}  // namespace
