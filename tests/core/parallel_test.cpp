#include "core/parallel.hpp"

#include <atomic>
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

}  // namespace
}  // namespace canalsim
