// Bytes the process holds from malloc, for tests of the memory statistics: glibc's own count (mallinfo2), so
// unavailable with another C library or when a sanitizer replaces malloc.
#ifndef HSLAM_TEST_HEAP_H
#define HSLAM_TEST_HEAP_H

#include <cstddef>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define HSLAM_TEST_SANITIZED_HEAP 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define HSLAM_TEST_SANITIZED_HEAP 1
#endif
#endif

namespace hslam_test
{
//! True when heapInUse() measures the heap.
inline bool heapMeasurable()
{
#if defined(__GLIBC__) && !defined(HSLAM_TEST_SANITIZED_HEAP)
  return true;
#else
  return false;
#endif
}

//! Bytes in use in malloc's blocks (0 when !heapMeasurable()).
inline std::size_t heapInUse()
{
#if defined(__GLIBC__) && !defined(HSLAM_TEST_SANITIZED_HEAP)
  return mallinfo2().uordblks;
#else
  return 0;
#endif
}
} // namespace hslam_test

#endif
