#include "core/parallel.hpp"
#include "core/progress.hpp"

#include <atomic>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace canalsim {
namespace {

TEST(ParallelFor, RunsEveryIndexExactlyOnceWhateverTheThreadCount) {
  for (int threads : {1, 2, 7}) {
    std::vector<int> runs(1000, 0);
    parallel_for(runs.size(), threads, [&](std::size_t i) { runs[i] += 1; });
    for (std::size_t i = 0; i < runs.size(); ++i) ASSERT_EQ(runs[i], 1) << "index " << i << ", threads " << threads;
  }
}

TEST(ParallelFor, UsesNoMoreThreadsThanAskedAndRunsInOrderOnOne) {
  std::vector<std::size_t> order;
  parallel_for(5, 1, [&](std::size_t i) { order.push_back(i); });
  EXPECT_EQ(order, (std::vector<std::size_t>{0, 1, 2, 3, 4}));

  std::atomic<int> running{0}, most{0};
  parallel_for(40, 3, [&](std::size_t) {
    const int now = ++running;
    for (int seen = most.load(); now > seen && !most.compare_exchange_weak(seen, now);) {}
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    --running;
  });
  EXPECT_LE(most.load(), 3);
}

TEST(ParallelFor, RethrowsTheLowestFailingIndexAfterRunningAll) {
  std::atomic<int> ran{0};
  try {
    parallel_for(50, 4, [&](std::size_t i) {
      ++ran;
      if (i == 31 || i == 17) throw std::runtime_error("index " + std::to_string(i));
    });
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "index 17");
  }
  EXPECT_EQ(ran.load(), 50);
}

TEST(ParallelFor, NothingToDoIsNotAnError) {
  parallel_for(0, 4, [](std::size_t) { FAIL(); });
}

// The counter of finished items: every count from 1 to the total once, the share rising to 1,
// whichever threads finish, and the callback never entered by two threads at once.
TEST(ProgressCounter, CountsEachFinishedItemOnceFromAnyThread) {
  std::vector<ProgressReport> reports;
  std::atomic<int> inside{0};
  bool overlapped = false;
  ProgressCounter counter(
      [&](const ProgressReport& r) {
        if (++inside > 1) overlapped = true;
        reports.push_back(r);
        std::this_thread::yield();
        --inside;
      },
      40);
  parallel_for(40, 4, [&](std::size_t) { counter.finished("cases"); });
  ASSERT_EQ(reports.size(), 40u);
  EXPECT_FALSE(overlapped);
  std::set<std::string> messages;
  for (std::size_t k = 0; k < reports.size(); ++k) {
    EXPECT_DOUBLE_EQ(reports[k].fraction, static_cast<double>(k + 1) / 40.0);
    messages.insert(reports[k].message);
  }
  EXPECT_EQ(reports.back().message, "40/40 cases");
  EXPECT_EQ(messages.size(), 40u);
}

TEST(ProgressCounter, WithoutACallbackItDoesNothing) {
  ProgressCounter counter(nullptr, 3);
  for (int i = 0; i < 5; ++i) counter.finished("items");  // more than the total: no report, no error
}

}  // namespace
}  // namespace canalsim
