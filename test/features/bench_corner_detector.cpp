// Cost of detectCorners with the defaults' settings (FAST 7, 4 px apart, ORB border) for a keyframe (250 corners:
// half of the 500-candidate budget) and for a frame tracked in hybrid mode (1000 corners), on the first frame of
// each real shared sequence, with the strong thresholds tried first (the default) and with one detection at
// threshold 7. Both give the same corners (unit test
// HybridTrackingTest.strongCornersFirstGiveTheCornersOfOneDetection).
#include "HSlamTestData.h"

#include "features/CornerDetector.h"
#include "features/PointDescriptors.h"

#include <visp3/io/vpImageIo.h>

#include <benchmark/benchmark.h>

#include <string>

namespace
{
const char *const kFrames[] = {"kitti06_000-050/image_0/000000.png", "7scenes_redkitchen_000-299/rgb/000000.jpg",
                               "tsukuba_cg_000-149/rgb/00000.jpg"};
const char *const kLabels[] = {"kitti06 1241x376", "7scenes 640x480", "tsukuba 640x480"};

void BM_DetectCorners(benchmark::State &state)
{
  const size_t which = static_cast<size_t>(state.range(0));
  const std::string path = hslam_test::sharedData(kFrames[which]);
  if (path.empty()) {
    state.SkipWithError("shared data not found");
    return;
  }
  vpImage<unsigned char> I;
  vpImageIo::read(I, path);
  hslam::CornerOptions options;
  options.threshold = 7;
  options.maxCorners = static_cast<int>(state.range(2));
  options.minDistance = 4.;
  options.border = hslam::kOrbBorderPx + 1;
  options.strongFirst = state.range(1) != 0;
  std::vector<cv::Point2f> corners;
  // As the callers do: the hint carried from one image to the next (here the same image, so it settles at once).
  hslam::CornerThresholdHint hint;
  for (auto _ : state) {
    hslam::detectCorners(I, options, corners, nullptr, &hint);
    benchmark::DoNotOptimize(corners.data());
  }
  state.counters["corners"] = static_cast<double>(corners.size());
  state.SetLabel(std::string(kLabels[which]) + ", " + std::to_string(options.maxCorners) +
                 (options.strongFirst ? " corners, strong first" : " corners, one detection"));
}
} // namespace

BENCHMARK(BM_DetectCorners)->ArgsProduct({{0, 1, 2}, {0, 1}, {250, 1000}})->Unit(benchmark::kMicrosecond);
