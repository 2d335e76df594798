// Per-keyframe cost of PixelSelector::select at 640x480, target 1500 (DSO's immature density), on a rendered
// synthetic frame (textured room) and on the first 7-Scenes frame when the shared data is present.
#include "HSlamTestData.h"

#include "features/ImagePyramid.h"
#include "features/PixelSelector.h"

#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/io/vpImageIo.h>

#include <benchmark/benchmark.h>

namespace
{
bool loadFrame(int which, vpImage<unsigned char> &I)
{
  if (which == 0) {
    if (hslam_test::vispImagesDir().empty()) {
      return false;
    }
    vpHSlamSyntheticScene scene;
    scene.configure(640, 480, 30, 30.0, 7);
    scene.render(3, I);
    return true;
  }
  const std::string path = hslam_test::sharedData("7scenes_redkitchen_000-299/rgb/000000.jpg");
  if (path.empty()) {
    return false;
  }
  vpImageIo::read(I, path);
  return true;
}

void BM_PixelSelector(benchmark::State &state)
{
  const int which = static_cast<int>(state.range(0));
  vpImage<unsigned char> I;
  if (!loadFrame(which, I)) {
    state.SkipWithError("frame data not found");
    return;
  }
  hslam::ImagePyramid pyramid;
  pyramid.build(I, hslam::PinholeIntrinsics{525., 525., 319.5, 239.5}, 6, 5000);
  const vpHSlamParameters::Features params;
  hslam::PixelSelector selector(params);
  std::vector<hslam::SelectedPixel> pixels;
  unsigned int seed = 0;
  int runs = 0;
  for (auto _ : state) {
    selector.select(pyramid, params.desiredImmatureDensity, seed++, pixels);
    runs += selector.lastRunCount();
    benchmark::DoNotOptimize(pixels.data());
  }
  state.counters["points"] = static_cast<double>(pixels.size());
  state.counters["runs/call"] = static_cast<double>(runs) / static_cast<double>(state.iterations());
  state.SetLabel(which == 0 ? "synthetic 640x480" : "7scenes 640x480");
}
} // namespace

BENCHMARK(BM_PixelSelector)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);
