/*
 * H-SLAM for ViSP.
 */
#include "common/WorkerPool.h"

namespace hslam
{
WorkerPool::WorkerPool(int threads)
{
  const int t = threads > 0 ? threads : 0;
  m_errors.resize(static_cast<size_t>(t) + 1);
  m_threads.reserve(static_cast<size_t>(t));
  for (int w = 1; w <= t; ++w) {
    m_threads.emplace_back([this, w] { workerLoop(w); });
  }
}

WorkerPool::~WorkerPool()
{
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stop = true;
  }
  m_workAvailable.notify_all();
  for (std::thread &t : m_threads) {
    t.join();
  }
}

void WorkerPool::chunk(size_t n, int participants, int worker, size_t &begin, size_t &end)
{
  // Balanced contiguous split: the first (n % p) chunks get one extra index.
  const size_t p = static_cast<size_t>(participants);
  const size_t w = static_cast<size_t>(worker);
  const size_t base = n / p, extra = n % p;
  begin = w * base + (w < extra ? w : extra);
  end = begin + base + (w < extra ? 1 : 0);
}

void WorkerPool::run(size_t n, const Task &fn)
{
  if (m_threads.empty()) {
    if (n > 0) {
      fn(0, 0, n);
    }
    return;
  }
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_task = &fn;
    m_n = n;
    m_pending = threads();
    for (std::exception_ptr &e : m_errors) {
      e = nullptr;
    }
    ++m_generation;
  }
  m_workAvailable.notify_all();
  size_t begin, end;
  chunk(n, participants(), 0, begin, end);
  std::exception_ptr own;
  if (begin < end) {
    try {
      fn(0, begin, end);
    } catch (...) {
      own = std::current_exception();
    }
  }
  std::unique_lock<std::mutex> lock(m_mutex);
  m_workDone.wait(lock, [this] { return m_pending == 0; });
  m_task = nullptr;
  m_errors[0] = own;
  for (const std::exception_ptr &e : m_errors) {
    if (e) {
      std::exception_ptr first = e;
      lock.unlock();
      std::rethrow_exception(first);
    }
  }
}

void WorkerPool::workerLoop(int worker)
{
  unsigned long seen = 0;
  std::unique_lock<std::mutex> lock(m_mutex);
  for (;;) {
    m_workAvailable.wait(lock, [this, seen] { return m_stop || m_generation != seen; });
    if (m_stop) {
      return;
    }
    seen = m_generation;
    const Task *task = m_task;
    const size_t n = m_n;
    lock.unlock();
    size_t begin, end;
    chunk(n, participants(), worker, begin, end);
    std::exception_ptr error;
    if (begin < end) {
      try {
        (*task)(worker, begin, end);
      } catch (...) {
        error = std::current_exception();
      }
    }
    lock.lock();
    m_errors[static_cast<size_t>(worker)] = error;
    if (--m_pending == 0) {
      m_workDone.notify_one();
    }
  }
}
} // namespace hslam
