/*
 * H-SLAM for ViSP.
 */
/*!
  \file WorkerPool.h
  \brief A small persistent pool of threads that splits an index range [0, n) into contiguous chunks.
*/
#ifndef HSLAM_COMMON_WORKER_POOL_H
#define HSLAM_COMMON_WORKER_POOL_H

#include <visp3/core/vpConfig.h>

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace hslam
{
/*!
  Persistent worker threads for data-parallel passes (the window bundle adjustment's residual accumulation).

  WorkerPool(t) starts t threads once; run(n, fn) splits [0, n) into (t + 1) contiguous chunks, chunk w going to
  participant w: worker threads take chunks 1..t and the CALLER takes chunk 0, so with t = 0 run() is a plain call
  fn(0, 0, n) in the caller and no thread exists. The split depends only on n and t, so a caller that keeps one
  accumulator per participant and merges them in participant order gets results that are deterministic for a
  given thread count. Empty chunks are not called.

  Ownership / threading: the pool owns its threads; the destructor wakes and joins them. run() must be called by
  one thread at a time (the owner, e.g. the mapping thread) and is not re-entrant (fn must not call run() of the
  same pool). run() returns only when every chunk has finished; \e fn is called concurrently from several threads
  with disjoint ranges, so it must only write state private to its participant index or its range. The first
  exception thrown by any chunk (the caller's chunk first, then workers in index order) is rethrown by run() after
  all chunks have finished. One mutex and two condition variables (work available / work done) synchronise it.

  \code
  hslam::WorkerPool pool(2);
  std::vector<double> partial(pool.participants(), 0.);
  pool.run(values.size(), [&](int w, size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) partial[w] += values[i];
  });
  double sum = 0.;
  for (double p : partial) sum += p; // fixed order: deterministic
  \endcode
*/
class VISP_EXPORT WorkerPool
{
public:
  using Task = std::function<void(int worker, size_t begin, size_t end)>;

  //! Start \e threads worker threads (0: none, run() executes in the caller). Negative counts are treated as 0.
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool &) = delete;
  WorkerPool &operator=(const WorkerPool &) = delete;

  //! Worker threads (not counting the caller).
  int threads() const { return static_cast<int>(m_threads.size()); }
  //! Participants of run(): threads() + 1 (the caller is participant 0).
  int participants() const { return threads() + 1; }

  //! Chunk [begin, end) of participant \e worker when [0, n) is split over \e participants.
  static void chunk(size_t n, int participants, int worker, size_t &begin, size_t &end);

  //! Run \e fn over [0, n) split in participants() contiguous chunks; waits for all; rethrows a chunk's exception.
  void run(size_t n, const Task &fn);

private:
  void workerLoop(int worker);

  std::vector<std::thread> m_threads;
  std::mutex m_mutex;
  std::condition_variable m_workAvailable;
  std::condition_variable m_workDone;
  const Task *m_task = nullptr;
  size_t m_n = 0;
  unsigned long m_generation = 0; //!< incremented per run(): a worker runs each generation once
  int m_pending = 0;              //!< worker chunks of the current generation not finished yet
  bool m_stop = false;
  std::vector<std::exception_ptr> m_errors; //!< per participant, of the current run
};
} // namespace hslam

#endif
