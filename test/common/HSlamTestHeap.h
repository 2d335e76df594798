// Bytes the process holds from malloc, for tests of the memory statistics: glibc's own count (mallinfo2), used only
// when it is seen to count an allocation. A sanitizer's runtime (the CI's AddressSanitizer pass links uninstrumented
// test programs with it), a preloaded allocator or valgrind replace malloc but not mallinfo2, whose count then stays
// still.
#ifndef HSLAM_TEST_HEAP_H
#define HSLAM_TEST_HEAP_H

#include <cstddef>
#include <cstdlib>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hslam_test
{
//! Bytes in use in malloc's blocks, those served by mmap included (0 without glibc).
inline double heapInUse()
{
#if defined(__GLIBC__)
  const struct mallinfo2 info = mallinfo2();
  return static_cast<double>(info.uordblks) + static_cast<double>(info.hblkhd);
#else
  return 0.;
#endif
}

//! True when heapInUse() measures this process's allocations: a 4000-byte block must move it by 4000-4100 bytes.
inline bool heapMeasurable()
{
  static void *volatile sink = nullptr; // keeps the compiler from eliding the allocations
  sink = std::malloc(16);               // a thread's first allocation also sets up malloc's per-thread cache
  std::free(sink);
  const double before = heapInUse();
  sink = std::malloc(4000);
  const double grown = heapInUse() - before;
  std::free(sink);
  sink = nullptr;
  return grown >= 4000. && grown <= 4100.;
}
} // namespace hslam_test

#endif
