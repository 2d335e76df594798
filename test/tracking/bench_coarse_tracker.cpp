// Time of one CoarseTracker::track() at 640x480 with ~2000 reference points (synthetic scene, exact depths), and of
// setReference() (inverse-depth maps and point lists).
#include "HSlamTestData.h"
#include "TrackingTestUtils.h"

#include <benchmark/benchmark.h>

using namespace hslam;

namespace
{
constexpr unsigned int kWidth = 640;
constexpr unsigned int kHeight = 480;
constexpr int kPoints = 2000;
constexpr unsigned int kTargetFrame = 3;

struct Setup {
  vpHSlamParameters::Tracker params;
  vpHSlamSyntheticScene scene;
  Frame reference, target;
  std::vector<CoarseTrackerPoint> points;
  bool ok = false;
  Setup()
  {
    if (hslam_test::vispImagesDir().empty()) {
      return;
    }
    scene.configure(kWidth, kHeight, 100, 30.0, 1);
    hslam_test::makeFrame(scene, 0, params, reference);
    hslam_test::makeFrame(scene, kTargetFrame, params, target);
    points = hslam_test::selectPoints(scene, 0, reference, kPoints);
    ok = true;
  }
};

Setup &setup()
{
  static Setup s;
  return s;
}

void BM_CoarseTrackerTrack(benchmark::State &state)
{
  Setup &s = setup();
  if (!s.ok) {
    state.SkipWithError("visp-images-data not installed");
    return;
  }
  CoarseTracker tracker(s.params);
  tracker.setReference(s.reference, s.points);
  int iterations = 0;
  for (auto _ : state) {
    SE3d newMref; // zero-motion start, as after a keyframe change
    AffineBrightness affine;
    CoarseTrackingResult result;
    benchmark::DoNotOptimize(tracker.track(s.target, newMref, affine, result));
    iterations = result.iterations;
  }
  state.counters["points"] = static_cast<double>(s.points.size());
  state.counters["residuals_l0"] = tracker.numPoints(0);
  state.counters["gn_iterations"] = iterations;
}
BENCHMARK(BM_CoarseTrackerTrack)->Unit(benchmark::kMillisecond);

void BM_CoarseTrackerSetReference(benchmark::State &state)
{
  Setup &s = setup();
  if (!s.ok) {
    state.SkipWithError("visp-images-data not installed");
    return;
  }
  CoarseTracker tracker(s.params);
  for (auto _ : state) {
    tracker.setReference(s.reference, s.points);
  }
}
BENCHMARK(BM_CoarseTrackerSetReference)->Unit(benchmark::kMillisecond);
} // namespace
