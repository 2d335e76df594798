// Per-frame cost of vpHSlamRectifier::rectify (8-bit and float) and the one-time cost of building the table.
//   pinhole none 640x480 (plain copy), radtan crop 640x480, EuRoC radtan crop 752x480.
#include "CameraTestFixtures.h"

#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamRectifier.h>

#include <benchmark/benchmark.h>

#include <random>

using hslam_test::eurocRadTan;
using hslam_test::pinholeVga;
using hslam_test::radTanVga;

namespace
{
vpHSlamCamera cameraOf(int which)
{
  switch (which) {
  case 0:
    return pinholeVga();
  case 1:
    return radTanVga();
  default:
    return eurocRadTan();
  }
}

const char *labelOf(int which)
{
  switch (which) {
  case 0:
    return "pinhole none 640x480";
  case 1:
    return "radtan crop 640x480";
  default:
    return "EuRoC radtan crop 752x480";
  }
}

template <typename Type> void BM_Rectify(benchmark::State &state)
{
  const vpHSlamCamera cam = cameraOf(static_cast<int>(state.range(0)));
  const vpHSlamRectifier rectifier(cam);
  vpImage<Type> I(cam.getHeight(), cam.getWidth());
  std::mt19937 rng(0);
  std::uniform_int_distribution<int> byte(0, 255);
  for (unsigned int k = 0; k < I.getSize(); ++k) {
    I.bitmap[k] = static_cast<Type>(byte(rng));
  }
  vpImage<Type> Irect;
  rectifier.rectify(I, Irect);
  for (auto _ : state) {
    rectifier.rectify(I, Irect);
    benchmark::DoNotOptimize(Irect.bitmap);
    benchmark::ClobberMemory();
  }
  state.SetLabel(labelOf(static_cast<int>(state.range(0))));
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(Irect.getSize()));
}

void BM_BuildRectifier(benchmark::State &state)
{
  const vpHSlamCamera cam = cameraOf(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    vpHSlamRectifier rectifier(cam);
    benchmark::DoNotOptimize(rectifier.getWidth());
  }
  state.SetLabel(labelOf(static_cast<int>(state.range(0))));
}
} // namespace

BENCHMARK_TEMPLATE(BM_Rectify, unsigned char)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Rectify, float)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildRectifier)->DenseRange(1, 2)->Unit(benchmark::kMillisecond);
