// Test helpers: random 256-bit ORB descriptors and noisy copies of them (a descriptor seen again from another view).
#ifndef HSLAM_TEST_DESCRIPTORS_H
#define HSLAM_TEST_DESCRIPTORS_H

#include "features/BinaryDescriptor.h"

#include <cstdint>
#include <random>

namespace hslam_test
{
//! A descriptor with every bit drawn at random.
inline hslam::OrbDescriptor randomDescriptor(std::mt19937_64 &rng)
{
  hslam::OrbDescriptor d;
  for (auto &w : d.words) {
    w = rng();
  }
  return d;
}

//! \e d with \e bits randomly chosen bits flipped (a bit may be drawn twice).
inline hslam::OrbDescriptor flipBits(hslam::OrbDescriptor d, int bits, std::mt19937_64 &rng)
{
  for (int i = 0; i < bits; ++i) {
    const int b = static_cast<int>(rng() % 256);
    d.words[static_cast<std::size_t>(b >> 6)] ^= std::uint64_t(1) << (b & 63);
  }
  return d;
}
} // namespace hslam_test

#endif
