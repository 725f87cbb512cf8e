// A malformed sweep file is one InputError naming the file, the line and the key, before any
// case runs: unknown keys, empty lists and ranges, counts below 1, a distribution without a seed,
// low >= high, unknown experiments and models, and scenario keys the scenario refuses.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/errors.hpp"
#include "sweep/sweep_file.hpp"

namespace canalsim::sweep {
namespace {

struct Malformed {
  std::string text;
  std::string where;     // "bad.toml:LINE:"
  std::string expected;  // a part of the message
};

std::string message_of(const std::string& text) {
  try {
    parse_sweep_file(text, "bad.toml", ".");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

const std::string kHead = "scenario = \"lab\"\nexperiments = [\"op1\"]\n";  // lines 1-2

TEST(SweepFile, EachMalformedFileIsOneLineNamingItsLine) {
  const std::vector<Malformed> cases = {
      {"scenario = \"lab\"\nexperiments = [\"op1\"\n", "bad.toml:2:", "not valid TOML"},
      {kHead + "colour = \"red\"\n[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n", "bad.toml:3:",
       "unknown key colour"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalus = [4.0]\n", "bad.toml:5:", "unknown key vary[0].valus"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = []\n", "bad.toml:5:", "values: empty"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nfrom = 4.0\nto = 6.0\ncount = 0\n", "bad.toml:7:",
       "vary[0].count = 0: expected an integer in [1, 100000]"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nfrom = 4.0\nto = 4.0\ncount = 3\n", "bad.toml:6:",
       "vary[0].to: equal to from"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nfrom = 4.0\ncount = 3\n", "bad.toml:3:", "vary[0].to: missing"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nfrom = -1.0\nto = 4.0\ncount = 3\nspacing = \"log\"\n",
       "bad.toml:8:", "needs from > 0 and to > 0"},
      {kHead + "[[vary]]\nkey = \"pools[1].manning_n\"\ndistribution = \"uniform\"\nlow = 0.01\nhigh = 0.02\n",
       "bad.toml:4:", "needs a seed"},
      {"seed = 1\n" + kHead + "[[vary]]\nkey = \"pools[1].manning_n\"\ndistribution = \"uniform\"\nlow = 0.012\nhigh = 0.009\n",
       "bad.toml:8:", "vary[0].high: not above low: expected low < high"},
      {"seed = 1\n" + kHead + "[[vary]]\nkey = \"pools[1].manning_n\"\ndistribution = \"normal\"\nmean = 0.01\nstd = 0\n",
       "bad.toml:8:", "vary[0].std = 0: expected a number in (0, ∞)"},
      {"seed = 1\n" + kHead + "[[vary]]\nkey = \"pools[1].manning_n\"\ndistribution = \"gamma\"\n", "bad.toml:6:",
       "expected one of uniform, normal, lognormal"},
      {"draws = 5\n" + kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n", "bad.toml:1:",
       "draws: without a distribution"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\nlow = 1.0\n", "bad.toml:6:",
       "vary[0].low: belongs to a distribution"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\nfrom = 1.0\n", "bad.toml:3:",
       "vary[0]: expected one of values"},
      {"scenario = \"lab\"\nexperiments = [\"op1\", \"op9\"]\n[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n",
       "bad.toml:2:", "\"op9\" is not an experiment of builtin:lab"},
      {"scenario = \"nowhere.toml\"\nexperiments = [\"op1\"]\n", "bad.toml:1:", "scenario = nowhere.toml: expected a built-in scenario"},
      {kHead + "[[vary]]\nkey = \"pools[1].lenght_m\"\nvalues = [4.0]\n", "bad.toml:4:",
       "vary[0].key = pools[1].lenght_m = 4: expected a key and value the scenario takes"},
      {kHead + "[[vary]]\nkey = \"pools[2].length_m\"\nvalues = [4.0]\n", "bad.toml:4:", "the file has no table pools[2]"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n[[vary]]\nkey = \"pools[1].manning_n\"\n"
               "values = [0.01,\n0.5]\n",
       "bad.toml:9:", "vary[1].key = pools[1].manning_n = 0.5"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n[[vary]]\nkey = \"pools[1].length_m\"\n"
               "values = [5.0]\n",
       "bad.toml:7:", "already varied at line 4"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n[compute]\nfit = [\"LFOMX\"]\n", "bad.toml:7:",
       "\"LFOMX\" is not a reduced model"},
      {kHead + "[[vary]]\nkey = \"pools[1].length_m\"\nvalues = [4.0]\n[compute]\nsummary = false\n", "bad.toml:6:",
       "nothing to compute"},
      {kHead, "bad.toml:1:", "vary: missing"},
      {"experiments = [\"op1\"]\n", "bad.toml:1:", "scenario: missing"},
  };
  for (const auto& c : cases) {
    const std::string message = message_of(c.text);
    EXPECT_EQ(message.rfind(c.where, 0), 0u) << c.text << "\n-> " << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.text << "\n-> " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(SweepFile, AScenarioPathIsTakenFromTheSweepFilesFolder) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("sweep_file_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "runs");
  {
    std::ofstream(dir / "canal.toml") << "name = \"mine\"\n[upstream]\nkind = \"discharge\"\ndischarge_m3s = 0.01\n"
                                         "[[pools]]\nlength_m = 10.0\nbottom_width_m = 0.2\nwall_height_m = 0.5\n"
                                         "[downstream]\nkind = \"weir\"\n[[experiments]]\nname = \"rest\"\n"
                                         "[experiments.input]\nkind = \"constant\"\n";
    std::ofstream(dir / "runs" / "s.toml") << "scenario = \"../canal.toml\"\nexperiments = [\"rest\"]\n[[vary]]\n"
                                              "key = \"pools[1].manning_n\"\nvalues = [0.01]\n";
  }
  const SweepFile f = read_sweep_file(dir / "runs" / "s.toml");
  EXPECT_EQ(f.scenario, "../canal.toml");
  EXPECT_EQ(f.scenario_source, (dir / "runs" / "../canal.toml").string());
  EXPECT_EQ(f.experiment_entries, std::vector<int>{1});
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace canalsim::sweep
