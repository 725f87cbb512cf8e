// distribute() on one process, as every run outside mpirun uses it: each case once, results by
// index whatever the thread that computed them, skipped cases not run, the journal callback once
// per case, errors.
#include "cluster/distribute.hpp"

#include <atomic>
#include <mutex>
#include <chrono>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace canalsim::cluster {
namespace {

// A case whose cost varies by 20x with its index, as sweep cases do.
std::string uneven_case(std::size_t i) {
  std::this_thread::sleep_for(std::chrono::milliseconds(i % 5 == 0 ? 20 : 1));
  return "case " + std::to_string(i) + " squared " + std::to_string(i * i);
}

TEST(Distribute, OneProcessOutsideMpirun) {
  EXPECT_EQ(rank(), 0);
  EXPECT_EQ(processes(), 1);
  EXPECT_TRUE(is_root());
}

TEST(Distribute, EveryCaseOnceAndResultsByIndexWhateverTheThreads) {
  for (int threads : {1, 2, 5}) {
    std::atomic<int> calls{0};
    std::vector<std::size_t> journal;
    DistributeOptions options;
    options.threads = threads;
    options.on_result = [&](std::size_t index, const std::string& result) {
      journal.push_back(index);
      EXPECT_EQ(result, uneven_case(index));
    };
    const auto results = distribute(23, [&](std::size_t i) { ++calls; return uneven_case(i); }, options);
    ASSERT_EQ(results.size(), 23u);
    for (std::size_t i = 0; i < results.size(); ++i) EXPECT_EQ(results[i], uneven_case(i)) << threads << " threads";
    EXPECT_EQ(calls.load(), 23);
    EXPECT_EQ(journal.size(), 23u);
    EXPECT_EQ(std::set<std::size_t>(journal.begin(), journal.end()).size(), 23u) << "a case journalled twice";
  }
}

TEST(Distribute, SkippedCasesAreNotRun) {
  std::vector<bool> skip(10, false);
  skip[0] = skip[3] = skip[9] = true;
  std::set<std::size_t> ran;
  std::mutex mutex;
  DistributeOptions options;
  options.threads = 2;
  options.skip = skip;
  const auto results = distribute(10, [&](std::size_t i) {
    const std::lock_guard lock(mutex);
    ran.insert(i);
    return std::to_string(i);
  }, options);
  EXPECT_EQ(ran, (std::set<std::size_t>{1, 2, 4, 5, 6, 7, 8}));
  EXPECT_EQ(results[0], "");
  EXPECT_EQ(results[3], "");
  EXPECT_EQ(results[4], "4");
}

TEST(Distribute, NoCasesOrAllSkippedReturnAtOnce) {
  EXPECT_TRUE(distribute(0, [](std::size_t) { return std::string("x"); }, {}).empty());
  DistributeOptions options;
  options.skip = {true, true};
  EXPECT_EQ(distribute(2, [](std::size_t) -> std::string { throw std::logic_error("ran"); }, options),
            (std::vector<std::string>{"", ""}));
}

TEST(Distribute, AnEscapedErrorIsRethrownForTheLowestCase) {
  DistributeOptions options;
  options.threads = 3;
  try {
    distribute(12, [](std::size_t i) -> std::string {
      if (i == 4 || i == 9) throw std::runtime_error("case " + std::to_string(i) + " failed");
      return {};
    }, options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "case 4 failed");
  }
}

}  // namespace
}  // namespace canalsim::cluster
