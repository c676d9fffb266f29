// ThreadPool: every index runs exactly once per loop, loops can follow each other, an exception reaches the caller.
#include "implicit_sim/core/base/thread_pool.h"

#include <atomic>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace implicit_sim {
namespace {

struct Counts {
  std::vector<std::atomic<int>> runs;
  explicit Counts(int n) : runs(n) {}
};

void CountIndex(void* context, int index) { static_cast<Counts*>(context)->runs[index].fetch_add(1); }

TEST(ThreadPool, RunsEveryIndexOnceInEveryLoop) {
  for (int threads : {1, 2, 4}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (int n : {0, 1, 3, 100, 7}) {  // loops of several sizes, one after another on the same workers
      Counts counts(n);
      pool.Run(n, CountIndex, &counts);
      for (int i = 0; i < n; ++i) EXPECT_EQ(counts.runs[i].load(), 1) << "threads " << threads << " n " << n << " i " << i;
    }
  }
}

void ThrowAtFive(void* context, int index) {
  static_cast<std::atomic<int>*>(context)->fetch_add(1);
  if (index == 5) throw std::runtime_error("index 5 failed");
}

TEST(ThreadPool, AnExceptionReachesTheCallerAfterTheOtherIndices) {
  ThreadPool pool(3);
  std::atomic<int> calls{0};
  EXPECT_THROW(pool.Run(20, ThrowAtFive, &calls), std::runtime_error);
  EXPECT_EQ(calls.load(), 20);
  Counts counts(10);  // the pool still works afterwards
  pool.Run(10, CountIndex, &counts);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(counts.runs[i].load(), 1);
}

TEST(ThreadPool, ZeroThreadsMeansTheHardwaresCores) {
  EXPECT_GE(ResolveThreadCount(0), 1);
  EXPECT_EQ(ResolveThreadCount(3), 3);
}

}  // namespace
}  // namespace implicit_sim
