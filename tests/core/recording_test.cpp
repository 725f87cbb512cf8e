// Recording CSV format (docs/recording-format.md): parsing, validation messages, round trip and
// atomic writes.
#include "core/recording.hpp"

#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <sstream>

#include "testing/refusals.hpp"

namespace canalsim {
namespace {

std::string message_of(const std::string& text) {
  return testing::input_error_of([&] { (void)parse_recording(text, "rec.csv"); });
}

TEST(Recording, ParsesMetadataHeaderAndRowsInPaperUnits) {
  const auto rec = parse_recording(
      "# experiment: op1\n# sampling_period_s: 0.13\n"
      "t_s,u_mm,y_dwe_mm,regime\n0,15,50.05,submerged\n0.13,20,50.10,free\n0.26,20,50.2,free\n",
      "rec.csv");
  EXPECT_EQ(rec.meta("experiment"), "op1");
  EXPECT_EQ(rec.size(), 3u);
  EXPECT_DOUBLE_EQ(rec.sample_period(), 0.13);
  EXPECT_DOUBLE_EQ(rec.column("y_dwe_mm")[1], 50.10);
  EXPECT_EQ(rec.column("regime")[0], static_cast<double>(RegimeCode::submerged));
  EXPECT_EQ(rec.column("regime")[1], static_cast<double>(RegimeCode::free));
}

// A file's own column names are read as canalsim's (RecordingReadOptions::column_names); a name
// mapped onto a column canalsim's name also heads would make the reader guess, so it refuses.
TEST(Recording, AFilesOwnColumnNamesAreReadAsCanalsimsWhenMapped) {
  RecordingReadOptions options;
  options.column_names = {{"t_s", "time"}, {"u_mm", "gate"}, {"y_dwe_mm", "level"}};
  const auto rec = parse_recording("time,gate,level,note\n0,15,50,1\n0.13,20,51,2\n", "own.csv", options);
  EXPECT_DOUBLE_EQ(rec.column("y_dwe_mm")[1], 51.0);
  EXPECT_DOUBLE_EQ(rec.sample_period(), 0.13);
  EXPECT_TRUE(rec.has("note"));
  try {
    parse_recording("time,gate,level,y_dwe_mm\n0,15,50,50\n0.13,20,51,51\n", "both.csv", options);
    ADD_FAILURE() << "a column named twice was read";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "both.csv:1: column level is to be read as y_dwe_mm, but the header has y_dwe_mm too: expected one of them");
  }
}

TEST(Recording, FormatThenParseGivesTheSameNumbers) {
  Recording rec;
  rec.set_column("t_s", {0.0, 0.13, 0.26});
  rec.set_column("u_mm", {15.0, 20.0, 10.0});
  rec.set_column("y_dwe_mm", {1.0 / 3.0, 2.0 / 7.0, 50.05});
  rec.set_column("regime", {0.0, 1.0, 0.0});
  rec.set_meta("experiment", "op2");
  const auto back = parse_recording(format_recording(rec), "mem");
  ASSERT_EQ(back.names, rec.names);
  for (std::size_t c = 0; c < rec.names.size(); ++c) {
    for (std::size_t i = 0; i < rec.size(); ++i) {
      EXPECT_NEAR(back.columns[c][i], rec.columns[c][i], 1e-9 * (1 + std::abs(rec.columns[c][i])));
    }
  }
  EXPECT_EQ(back.meta("experiment"), "op2");
}

TEST(Recording, MissingRequiredColumnIsNamedWithFileAndLine) {
  EXPECT_EQ(message_of("t_s,u_mm\n0,1\n0.1,2\n"),
            "rec.csv:1: missing required column y_dwe_mm (header has 2 columns)");
}

TEST(Recording, NonNumericAndNaNValuesNameLineAndColumn) {
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.1,x,3\n"),
            "rec.csv:3: column u_mm: expected a number, found 'x'");
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.1,1,nan\n"),
            "rec.csv:3: column y_dwe_mm: value is nan, expected a finite number");
}

TEST(Recording, TimeMustIncreaseUniformly) {
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.1,1,2\n0.1,1,2\n"), "rec.csv:4: t_s is not increasing (0.1 then 0.1)");
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm\n0,1,2\n0.1,1,2\n0.3,1,2\n"),
            "rec.csv:4: t_s is not uniformly sampled (step 0.2 s, expected 0.1 s, within 1 %); resample it "
            "first, e.g. canalsim resample rec.csv -o uniform.csv --period 0.15");
}

TEST(Recording, RowOfWrongLengthAndMissingHeaderAreRejected) {
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm\n0,1\n"), "rec.csv:2: expected 3 fields, found 2");
  EXPECT_EQ(message_of("# only: metadata\n"),
            "rec.csv: only comments and blank lines, no header line (expected column names, e.g. t_s,u_mm,y_dwe_mm)");
  EXPECT_EQ(message_of(""), "rec.csv: the file is empty, no header line (expected column names, e.g. t_s,u_mm,y_dwe_mm)");
  // Data without a header: said as such, not as a duplicate "column" 0.
  EXPECT_EQ(message_of("0,20,44\n0.13,20,44\n"),
            "rec.csv:1: the first line is numbers, not a header (expected column names, e.g. t_s,u_mm,y_dwe_mm)");
}

TEST(Recording, RegimeIsFreeOrSubmerged) {
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm,regime\n0,1,2,free\n0.1,1,2,weird\n"),
            "rec.csv:3: column regime: expected free, submerged, 0 or 1, found 'weird'");
  EXPECT_EQ(message_of("t_s,u_mm,y_dwe_mm,regime\n0,1,2,free\n0.1,1,2,1\n"), "");
}

TEST(Recording, DirectoryIsNotReadAsAnEmptyFile) {
  const auto dir = std::filesystem::temp_directory_path();
  try {
    read_recording(dir);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), dir.string() + ": is a directory, expected a recording");
  }
}

TEST(Recording, UnreadableFileIsNamed) {
  try {
    read_recording("/nonexistent/dir/rec.csv");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/dir/rec.csv: cannot open the recording for reading (no such file)");
  }
}

TEST(Recording, AtomicWriteReplacesWholeFileAndFailureKeepsTheOldOne) {
  const auto dir = std::filesystem::temp_directory_path() / "canalsim_recording_test";
  std::filesystem::create_directories(dir);
  const auto file = dir / "out.csv";
  write_file_atomically(file, "old contents\n");
  write_file_atomically(file, "new contents\n");
  std::ifstream in(file);
  std::stringstream got;
  got << in.rdbuf();
  EXPECT_EQ(got.str(), "new contents\n");
  EXPECT_THROW(write_file_atomically(dir / "missing_dir" / "x.csv", "data"), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir / "missing_dir"));
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename(), "out.csv") << "a temporary file was left behind";
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace canalsim
