/*
 * H-SLAM for ViSP.
 */
// WorkerPool: chunking, every index visited exactly once, exceptions reach the caller, 0 threads = caller only.
#include "HSlamTestData.h"

#include "common/WorkerPool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

using hslam::WorkerPool;

TEST(WorkerPool, EveryIndexVisitedOnceInContiguousChunks)
{
  for (int threads : {0, 1, 2, 3}) {
    WorkerPool pool(threads);
    ASSERT_EQ(pool.participants(), threads + 1);
    // Sizes below, equal to and above the participant count (empty chunks must be skipped).
    for (size_t n : {size_t(0), size_t(1), size_t(2), size_t(5), size_t(1000), size_t(1001)}) {
      std::vector<std::atomic<int>> visits(n);
      for (auto &v : visits) {
        v = 0;
      }
      std::vector<int> calls(static_cast<size_t>(pool.participants()), 0);
      pool.run(n, [&](int w, size_t begin, size_t end) {
        size_t eb, ee;
        WorkerPool::chunk(n, pool.participants(), w, eb, ee);
        EXPECT_EQ(begin, eb);
        EXPECT_EQ(end, ee);
        EXPECT_LT(begin, end);
        ++calls[static_cast<size_t>(w)];
        for (size_t i = begin; i < end; ++i) {
          ++visits[i];
        }
      });
      for (size_t i = 0; i < n; ++i) {
        EXPECT_EQ(visits[i].load(), 1) << "threads " << threads << " n " << n << " index " << i;
      }
      for (int c : calls) {
        EXPECT_LE(c, 1);
      }
    }
  }
}

TEST(WorkerPool, ChunksAreBalancedAndCoverTheRange)
{
  size_t prevEnd = 0;
  for (int w = 0; w < 3; ++w) {
    size_t b, e;
    WorkerPool::chunk(10, 3, w, b, e);
    EXPECT_EQ(b, prevEnd);
    EXPECT_GE(e - b, 3u);
    EXPECT_LE(e - b, 4u);
    prevEnd = e;
  }
  EXPECT_EQ(prevEnd, 10u);
}

TEST(WorkerPool, ZeroThreadsRunsInTheCaller)
{
  WorkerPool pool(0);
  EXPECT_EQ(pool.threads(), 0);
  const std::thread::id caller = std::this_thread::get_id();
  int calls = 0;
  pool.run(17, [&](int w, size_t begin, size_t end) {
    EXPECT_EQ(std::this_thread::get_id(), caller);
    EXPECT_EQ(w, 0);
    EXPECT_EQ(begin, 0u);
    EXPECT_EQ(end, 17u);
    ++calls;
  });
  EXPECT_EQ(calls, 1);
}

TEST(WorkerPool, WorkersRunOnOtherThreadsAndCallerTakesChunkZero)
{
  WorkerPool pool(2);
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<std::thread::id> ids(3);
  pool.run(30, [&](int w, size_t, size_t) { ids[static_cast<size_t>(w)] = std::this_thread::get_id(); });
  EXPECT_EQ(ids[0], caller);
  EXPECT_NE(ids[1], caller);
  EXPECT_NE(ids[2], caller);
  EXPECT_NE(ids[1], ids[2]);
}

TEST(WorkerPool, ExceptionInWorkerIsRethrownInCaller)
{
  WorkerPool pool(2);
  std::atomic<int> finished{0};
  EXPECT_THROW(pool.run(30,
                        [&](int w, size_t, size_t) {
                          if (w == 2) {
                            throw std::runtime_error("worker 2 failed");
                          }
                          ++finished;
                        }),
               std::runtime_error);
  // The other chunks still ran to completion before run() returned.
  EXPECT_EQ(finished.load(), 2);
  // The pool stays usable after an exception.
  std::atomic<size_t> total{0};
  pool.run(300, [&](int, size_t begin, size_t end) { total += end - begin; });
  EXPECT_EQ(total.load(), 300u);
  // An exception in the caller's own chunk as well.
  EXPECT_THROW(pool.run(30,
                        [&](int w, size_t, size_t) {
                          if (w == 0) {
                            throw std::logic_error("caller chunk failed");
                          }
                        }),
               std::logic_error);
}

TEST(WorkerPool, ManyRunsAccumulateDeterministically)
{
  WorkerPool pool(3);
  std::vector<double> values(10007);
  for (size_t i = 0; i < values.size(); ++i) {
    values[i] = 1. / static_cast<double>(i + 1);
  }
  double first = 0.;
  for (int rep = 0; rep < 200; ++rep) {
    std::vector<double> partial(static_cast<size_t>(pool.participants()), 0.);
    pool.run(values.size(), [&](int w, size_t begin, size_t end) {
      for (size_t i = begin; i < end; ++i) {
        partial[static_cast<size_t>(w)] += values[i];
      }
    });
    double sum = 0.;
    for (double p : partial) {
      sum += p;
    }
    if (rep == 0) {
      first = sum;
    }
    EXPECT_EQ(sum, first);
  }
  EXPECT_NEAR(first, 9.7885, 1e-3); // harmonic number H_10007 ~ ln(10007) + 0.5772
}
