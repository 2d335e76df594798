/*
 * H-SLAM for ViSP.
 */
#ifndef HSLAM_COMMON_HEAP_BYTES_H
#define HSLAM_COMMON_HEAP_BYTES_H

// What containers hold on the heap, allocator overhead included, for the memory statistics
// (vpHSlam::Statistics::mapMemoryMbPerKeyframe). Counting only the elements' sizes missed a third of what the
// global map holds: a stored point has two small vectors of its own, and the keyframe database a hash node and a
// vector per word, whose headers, rounding and growth slack cost more than their contents (measured on the
// 4000-frame soak: 0.055 MB per keyframe counted against 0.08-0.09 MB of heap growth per keyframe).
//
// The model is glibc's malloc on 64-bit (8-byte header, 16-byte granularity, 32-byte minimum chunk) and
// libstdc++'s node layouts (red-black tree node: colour and three links before the value; hash node: one link
// before the value, the hash not cached for integer keys). Other allocators differ by a few bytes per block.

#include <cstddef>
#include <map>
#include <unordered_map>
#include <vector>

namespace hslam
{
//! Bytes a heap block of \e requested bytes takes (0 for none).
inline double heapBlockBytes(std::size_t requested)
{
  if (requested == 0) {
    return 0.;
  }
  constexpr std::size_t kHeader = sizeof(std::size_t), kAlign = 16, kMinChunk = 32;
  const std::size_t chunk = (requested + kHeader + kAlign - 1) / kAlign * kAlign;
  return static_cast<double>(chunk < kMinChunk ? kMinChunk : chunk);
}

//! Heap bytes of a vector's buffer (its capacity, not its size).
template <typename T> double vectorHeapBytes(const std::vector<T> &v)
{
  return heapBlockBytes(v.capacity() * sizeof(T));
}

//! Heap bytes of one node of a std::map type (without what its value holds itself).
template <typename Map> double treeNodeHeapBytes()
{
  constexpr std::size_t kNodeHeader = 4 * sizeof(void *); // colour (padded) and parent, left, right links
  return heapBlockBytes(kNodeHeader + sizeof(typename Map::value_type));
}

//! Heap bytes of a std::map's nodes (without what the values hold themselves).
template <typename K, typename V, typename C, typename A> double mapNodesHeapBytes(const std::map<K, V, C, A> &m)
{
  return static_cast<double>(m.size()) * treeNodeHeapBytes<std::map<K, V, C, A>>();
}

//! Heap bytes of one node of a std::unordered_map type (without what its value holds itself).
template <typename Map> double hashNodeHeapBytes()
{
  return heapBlockBytes(sizeof(void *) + sizeof(typename Map::value_type));
}

//! Heap bytes of a std::unordered_map's bucket array.
template <typename K, typename V, typename H, typename E, typename A>
double hashBucketsHeapBytes(const std::unordered_map<K, V, H, E, A> &m)
{
  return heapBlockBytes(m.bucket_count() * sizeof(void *));
}
} // namespace hslam

#endif
