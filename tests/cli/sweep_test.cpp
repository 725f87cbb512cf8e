// `canalsim sweep`: a malformed sweep file is one error line naming its line, and nothing is
// written; an unfinished sweep's journal is not overwritten; the small example runs and writes
// its table, report and copy.
#include <gtest/gtest.h>

#include "testing/cli_run.hpp"
#include "tests/cli/expect_error.hpp"

namespace {

using namespace canalsim::cli_test;
namespace fs = std::filesystem;

TEST(Sweep, AMalformedFileIsOneErrorLineNamingItsLineAndNothingIsWritten) {
  const fs::path scratch = scratch_dir("sweep_malformed");
  const std::vector<std::pair<std::string, std::string>> files = {
      {"scenario = \"lab\"\nexperiments = [\"op1\"]\n[[vary]]\nkey = \"pools[1].length_m\"\nvalues = []\n",
       "bad.toml:5: vary[0].values: empty"},
      {"scenario = \"lab\"\nexperiments = [\"op1\"]\n[[vary]]\nkey = \"pools[1].lenght_m\"\nvalues = [4.0]\n",
       "bad.toml:4: vary[0].key = pools[1].lenght_m = 4: expected a key and value the scenario takes"},
      {"scenario = \"lab\"\nexperiments = [\"op7\"]\n", "bad.toml:2: experiments: \"op7\" is not an experiment"},
  };
  for (const auto& [text, message] : files) {
    std::ofstream(scratch / "bad.toml") << text;
    const std::size_t before = entry_count(scratch);
    const RunResult r = run_canalsim("sweep bad.toml --out out", scratch);
    EXPECT_TRUE(fails_naming(r, message));
    EXPECT_EQ(entry_count(scratch), before) << "nothing written for " << text;
    EXPECT_FALSE(fs::exists(scratch / "out"));
  }
  fs::remove_all(scratch);
}

TEST(Sweep, AnUnfinishedSweepsJournalIsNeitherOverwrittenNorResumedByAnotherFile) {
  const fs::path scratch = scratch_dir("sweep_journal");
  const std::string sweep = "scenario = \"lab\"\nexperiments = [\"op1\"]\nduration_s = 5\n[[vary]]\n"
                            "key = \"pools[1].cells\"\nvalues = [1000000]\n";
  std::ofstream(scratch / "a.toml") << sweep;
  std::ofstream(scratch / "b.toml") << sweep << "# another file\n";
  fs::create_directories(scratch / "out");
  std::ofstream(scratch / "out" / "table.partial.csv") << "# canalsim sweep journal of a.toml, fingerprint 0\n";
  const RunResult fresh = run_canalsim("sweep a.toml --out out", scratch);
  EXPECT_TRUE(fails_naming(fresh, "expected --resume"));
  const RunResult other = run_canalsim("sweep b.toml --out out --resume", scratch);
  EXPECT_TRUE(fails_naming(other, "the journal of another sweep file"));
  EXPECT_EQ(read_text(scratch / "out" / "table.partial.csv"), "# canalsim sweep journal of a.toml, fingerprint 0\n");
  EXPECT_FALSE(fs::exists(scratch / "out" / "table.csv"));
  fs::remove_all(scratch);
}

TEST(Sweep, TheSmallExampleWritesItsTableReportAndCopy) {
  const fs::path scratch = scratch_dir("sweep_small");
  const fs::path example = fs::path(CANALSIM_SOURCE_DIR) / "examples" / "sweep_small.toml";
  const RunResult r = run_canalsim("sweep '" + example.string() + "' --out out --threads 2", scratch);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote out/table.csv"), std::string::npos) << r.out;
  const std::string table = read_text(scratch / "out" / "table.csv");
  EXPECT_EQ(table.rfind("case,point,experiment,pools[1].length_m,pools[1].manning_n,status,message,", 0), 0u) << table;
  EXPECT_NE(table.find("LFOM_lambda"), std::string::npos);
  EXPECT_NE(table.find("lin_lambda"), std::string::npos);
  EXPECT_EQ(table.find(",failed,"), std::string::npos) << table;
  EXPECT_EQ(read_text(scratch / "out" / "sweep.toml"), read_text(example));
  EXPECT_NE(read_text(scratch / "out" / "report.html").find("<svg"), std::string::npos);
  EXPECT_FALSE(fs::exists(scratch / "out" / "table.partial.csv"));
  fs::remove_all(scratch);
}

}  // namespace
