/*
 * H-SLAM for ViSP.
 */
/*!
  \file BinaryDescriptor.h
  \brief 256-bit ORB descriptors as four 64-bit words, with the Hamming distance and conversions from OpenCV rows.

  What it is for: the vocabulary tree, its training and descriptor matching compare millions of descriptors; four
  machine words compared with popcount are several times faster than cv::Mat rows and need no allocation.

  Byte order: byte j of the OpenCV descriptor row (bits 8j..8j+7, the j-th group of rBRIEF tests) is byte j of the
  little-endian word array, so conversions in both directions are exact and the bit numbering matches DBoW2's
  FORB (which stores the same 32 bytes).
*/
#ifndef HSLAM_FEATURES_BINARY_DESCRIPTOR_H
#define HSLAM_FEATURES_BINARY_DESCRIPTOR_H

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

namespace hslam
{
//! Bytes of an ORB descriptor (256 binary tests).
constexpr int kOrbDescriptorBytes = 32;

//! One 256-bit binary descriptor.
struct OrbDescriptor {
  std::array<std::uint64_t, 4> words{{0, 0, 0, 0}};

  bool operator==(const OrbDescriptor &other) const { return words == other.words; }
  bool operator!=(const OrbDescriptor &other) const { return words != other.words; }

  //! Byte j (0..31) of the descriptor, as stored in an OpenCV row.
  std::uint8_t byte(int j) const { return static_cast<std::uint8_t>(words[j >> 3] >> (8 * (j & 7))); }
  void setByte(int j, std::uint8_t value)
  {
    const int shift = 8 * (j & 7);
    words[j >> 3] = (words[j >> 3] & ~(std::uint64_t(0xff) << shift)) | (std::uint64_t(value) << shift);
  }
  //! Bit b (0..255).
  bool bit(int b) const { return (words[b >> 6] >> (b & 63)) & 1u; }
};

/*!
  Bits set in a word. The baseline x86-64 the build targets has no popcnt instruction, and there
  __builtin_popcountll is a call into libgcc; the inline bit-sliced count is several times faster (exact either way).
*/
inline int popcount64(std::uint64_t x)
{
#if defined(__POPCNT__) || !(defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__)))
  return __builtin_popcountll(x);
#else
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<int>((x * 0x0101010101010101ull) >> 56);
#endif
}

//! Hamming distance between two descriptors, 0..256.
inline int hammingDistance(const OrbDescriptor &a, const OrbDescriptor &b)
{
  return popcount64(a.words[0] ^ b.words[0]) + popcount64(a.words[1] ^ b.words[1]) +
         popcount64(a.words[2] ^ b.words[2]) + popcount64(a.words[3] ^ b.words[3]);
}

/*!
  The popcnt instruction, chosen at run time. The build targets Debian's baseline x86-64, which lacks it, but every
  x86-64 processor since 2008 has it: the hottest Hamming loop (the bag-of-words descent of every keyframe) is
  compiled twice, once for it (a function marked HSLAM_TARGET_POPCNT that inlines hammingDistanceBuiltin()) and once
  portable, and the first runs when cpuHasPopcnt(). The distances are the same either way.
*/
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__)) && !defined(__POPCNT__)
#define HSLAM_POPCNT_DISPATCH 1
#define HSLAM_TARGET_POPCNT __attribute__((target("popcnt")))
#else
#define HSLAM_POPCNT_DISPATCH 0
#define HSLAM_TARGET_POPCNT
#endif

//! True when the processor has popcnt and the build does not use it everywhere already (see above).
inline bool cpuHasPopcnt()
{
#if HSLAM_POPCNT_DISPATCH
  static const bool has = __builtin_cpu_supports("popcnt") != 0;
  return has;
#else
  return false;
#endif
}

/*!
  Hamming distance through __builtin_popcountll: one instruction once inlined into an HSLAM_TARGET_POPCNT function
  (the only place to use it when HSLAM_POPCNT_DISPATCH), a library call elsewhere.
*/
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline int
hammingDistanceBuiltin(const OrbDescriptor &a, const OrbDescriptor &b)
{
  return __builtin_popcountll(a.words[0] ^ b.words[0]) + __builtin_popcountll(a.words[1] ^ b.words[1]) +
         __builtin_popcountll(a.words[2] ^ b.words[2]) + __builtin_popcountll(a.words[3] ^ b.words[3]);
}

//! Descriptor from 32 bytes in OpenCV row order.
inline OrbDescriptor descriptorFromBytes(const std::uint8_t *bytes)
{
  OrbDescriptor d;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  std::memcpy(d.words.data(), bytes, kOrbDescriptorBytes); // byte j of the words is byte j of the row (see above)
#else
  for (int j = 0; j < kOrbDescriptorBytes; ++j) {
    d.setByte(j, bytes[j]);
  }
#endif
  return d;
}

//! Descriptors from the rows of a CV_8U matrix with 32 columns (as cv::ORB computes them). Other shapes: empty.
inline std::vector<OrbDescriptor> descriptorsFromMat(const cv::Mat &rows)
{
  std::vector<OrbDescriptor> out;
  if (rows.empty() || rows.type() != CV_8UC1 || rows.cols != kOrbDescriptorBytes) {
    return out;
  }
  out.reserve(static_cast<size_t>(rows.rows));
  for (int r = 0; r < rows.rows; ++r) {
    out.push_back(descriptorFromBytes(rows.ptr<std::uint8_t>(r)));
  }
  return out;
}
} // namespace hslam

#endif
