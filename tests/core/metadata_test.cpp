// A recording's metadata is checked where it is read: every key canalsim knows has a range, a key
// is given once, and keys that contradict each other or the rows are refused — each as one error
// naming the file, line and key. A value that fails is never silently replaced by a default.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "core/declared_units.hpp"
#include "core/errors.hpp"
#include "core/metadata.hpp"
#include "core/recording.hpp"
#include "testing/refusals.hpp"

namespace {

using namespace canalsim;

const std::string kRows = "t_s,u_mm,y_dwe_mm\n0,15,50\n0.13,20,50.1\n0.26,10,50.2\n";

std::string error_of(const std::string& text) {
  try {
    (void)parse_recording(text, "r.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Metadata, EveryKnownKeyHasARangeAndAMeaning) {
  for (const MetadataKey& key : known_metadata_keys()) {
    EXPECT_FALSE(key.meaning.empty()) << key.name;
    if (key.type == MetadataKey::Type::text) continue;
    EXPECT_LT(key.low, key.high) << key.name;
  }
  EXPECT_EQ(find_metadata_key("no_such_key"), nullptr);
  EXPECT_NE(find_metadata_key("operating_opening_mm"), nullptr);
}

TEST(Metadata, AMalformedValueNamesFileLineAndKey) {
  const struct {
    std::string line, expected;
  } cases[] = {
      {"# operating_opening_mm: fifteen", "r.csv:2: metadata operating_opening_mm: 'fifteen': expected a number of mm in [0, 100000]"},
      {"# operating_opening_mm: nan", "r.csv:2: metadata operating_opening_mm: 'nan': expected"},
      {"# operating_opening_mm: 1e300", "r.csv:2: metadata operating_opening_mm: '1e300': expected"},
      {"# operating_opening_mm: -5", "r.csv:2: metadata operating_opening_mm: '-5': expected"},
      {"# initial_y_up_mm: nan", "r.csv:2: metadata initial_y_up_mm: 'nan': expected a number of mm in (0, 100000]"},
      {"# initial_y_up_mm: 0", "r.csv:2: metadata initial_y_up_mm: '0': expected"},
      {"# u_scale_mm_per_unit: 1e300", "r.csv:2: metadata u_scale_mm_per_unit: '1e300': expected a number of mm per unit in [1e-06, 1000000]"},
      {"# y_scale_mm_per_unit: 1e-300", "r.csv:2: metadata y_scale_mm_per_unit: '1e-300': expected"},
      {"# stages: 9.5", "r.csv:2: metadata stages: '9.5': expected an integer in [2, 20]"},
  };
  for (const auto& c : cases) {
    const std::string text = "# experiment: op1\n" + c.line + "\n" + kRows;
    EXPECT_NE(error_of(text).find(c.expected), std::string::npos) << c.line << ": " << error_of(text);
  }
  // Within range, and keys canalsim does not know, are kept as they are.
  const Recording ok =
      parse_recording("# operating_opening_mm: 15\n# my_note: anything: at all\n" + kRows, "r.csv");
  EXPECT_EQ(metadata_number(ok, "operating_opening_mm"), 15.0);
  EXPECT_EQ(ok.meta("my_note"), "anything: at all");
}

TEST(Metadata, AKeyGivenTwiceOrKeysThatContradictAreRefused) {
  EXPECT_NE(error_of("# experiment: a\n# experiment: b\n" + kRows)
                .find("r.csv:2: metadata experiment given twice (first at r.csv:1)"),
            std::string::npos);
  EXPECT_NE(error_of("# u_unit: mm\n# u_scale_mm_per_unit: 10\n" + kRows)
                .find("r.csv:2: metadata u_scale_mm_per_unit: 10 contradicts u_unit: mm"),
            std::string::npos);
  EXPECT_NE(error_of("# sampling_period_s: 0.5\n" + kRows)
                .find("r.csv:1: metadata sampling_period_s: 0.5 s contradicts the t_s step of 0.13 s"),
            std::string::npos);
  EXPECT_EQ(error_of("# sampling_period_s: 0.13\n# u_unit: mm\n# u_scale_mm_per_unit: 1\n" + kRows), "");
}

// A spreadsheet's byte order mark is not part of the first key (or of the header's first column).
TEST(Metadata, AUtf8ByteOrderMarkIsSkipped) {
  const Recording with_meta = parse_recording("\xEF\xBB\xBF# operating_opening_mm: 15\n" + kRows, "r.csv");
  EXPECT_EQ(with_meta.meta("operating_opening_mm"), "15");
  const Recording header_first = parse_recording("\xEF\xBB\xBF" + kRows, "r.csv");
  EXPECT_TRUE(header_first.has("t_s"));
}

// The declared scales apply, and a value that overflows the reader's range once they do is an
// error naming the row and column: the reader's check holds after the units as before them.
TEST(Metadata, AValueOutOfRangeAfterItsUnitIsNamed) {
  const Recording r = parse_recording("# y_unit: km\n# y_scale_mm_per_unit: 1e6\nt_s,u_mm,y_dwe_mm\n0,15,50\n"
                                      "0.13,20,2e7\n",
                                      "r.csv");
  EXPECT_TRUE(canalsim::testing::refuses_input(
      [&] { (void)in_millimetres(r); },
      "r.csv:5: column y_dwe_mm: 2e+07 km is 2e+13 mm: expected a magnitude of at most 1e+12 mm"));
}

// docs/recording-format.md lists every key with the range the reader enforces.
TEST(Metadata, TheDocumentedTableIsTheReadersTable) {
  std::ifstream in(std::string(CANALSIM_SOURCE_DIR) + "/docs/recording-format.md");
  std::stringstream doc;
  doc << in.rdbuf();
  for (const MetadataKey& key : known_metadata_keys()) {
    const std::string row = "| `" + std::string(key.name) + "` | " + std::string(key.unit) + " | " +
                            metadata_range_text(key) + " | ";
    EXPECT_NE(doc.str().find(row), std::string::npos) << row;
  }
}

}  // namespace
