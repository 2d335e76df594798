// Per-frame cost of ImagePyramid::build at 640x480 (DSO level rule: 4 levels), from float and from 8-bit images.
#include "features/ImagePyramid.h"

#include <benchmark/benchmark.h>

#include <random>

namespace
{
template <typename Type> void BM_PyramidBuild(benchmark::State &state)
{
  vpImage<Type> I(480, 640);
  std::mt19937 rng(0);
  std::uniform_int_distribution<int> byte(0, 255);
  for (unsigned int i = 0; i < I.getSize(); ++i) {
    I.bitmap[i] = static_cast<Type>(byte(rng));
  }
  const hslam::PinholeIntrinsics K0{525., 525., 319.5, 239.5};
  hslam::ImagePyramid pyramid;
  for (auto _ : state) {
    pyramid.build(I, K0, 6, 5000);
    benchmark::DoNotOptimize(pyramid.level(0).color.data());
  }
  state.SetLabel("640x480, " + std::to_string(pyramid.numLevels()) + " levels");
}
} // namespace

BENCHMARK_TEMPLATE(BM_PyramidBuild, float)->Unit(benchmark::kMicrosecond);
BENCHMARK_TEMPLATE(BM_PyramidBuild, unsigned char)->Unit(benchmark::kMicrosecond);
