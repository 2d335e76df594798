// Global map (issue 9) through vpHSlam on a synthetic room driven twice around the same loop (320x240, hybrid
// tracking): vo-reuse keeps marginalised keyframes lean, re-uses their points on the second lap, builds the hybrid
// graph and exposes points and edges; vo-strict keeps nothing.
#include "HSlamTestData.h"
#include "SystemTestUtils.h"

#include <visp3/hslam/vpHSlam.h>

#include <gtest/gtest.h>

#include <iostream>

namespace
{
constexpr unsigned int kWidth = 320, kHeight = 240, kLaps = 2, kFramesPerLap = 200;
constexpr unsigned int kFrames = kLaps * kFramesPerLap + 1;

struct TwoLapRun {
  hslam_test::SystemRun run;
  std::vector<vpHSlam::MapPoint> points;
  std::vector<vpHSlam::GraphEdge> edges;
};

TwoLapRun runTwoLaps(const vpHSlamSyntheticScene &scene, vpHSlamParameters::Mode mode, unsigned int frames)
{
  vpHSlamParameters params;
  params.system.deterministic = true;
  params.system.mode = mode;
  params.tracking.mode = vpHSlamParameters::trackingHybrid;
  vpHSlam slam(hslam_test::syntheticCamera(scene), params);
  TwoLapRun r;
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < frames; ++i) {
    scene.render(i, I);
    r.run.states.push_back(slam.track(I, scene.getTimestamp(i)));
  }
  r.run.trajectory = slam.getTrajectory();
  r.run.statistics = slam.getStatistics();
  r.points = slam.getMapPoints();
  r.edges = slam.getGraphEdges();
  return r;
}
} // namespace

TEST(SystemGlobalMap, SecondLapReusesLeanStoredKeyframes)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  vpHSlamSyntheticScene scene;
  scene.setLaps(kLaps);
  scene.configure(kWidth, kHeight, kFrames, 30., 3);
  const TwoLapRun reuse = runTwoLaps(scene, vpHSlamParameters::modeVoReuse, kFrames);
  const vpHSlam::Statistics &s = reuse.run.statistics;
  const double ate = hslam_test::simAte(hslam_test::syntheticGroundTruth(scene, kFrames), reuse.run.trajectory);
  size_t active = 0;
  for (const vpHSlam::MapPoint &p : reuse.points) {
    active += p.active ? 1u : 0u;
  }
  size_t covisibility = 0;
  for (const vpHSlam::GraphEdge &e : reuse.edges) {
    covisibility += e.covisibility ? 1u : 0u;
    EXPECT_NE(e.a, e.b);
  }
  std::cout << "vo-reuse, 2 laps: tracked " << s.trackedFrames << "/" << kFrames << ", keyframes " << s.keyframes
            << " (" << s.marginalizedKeyframes << " stored, " << s.culledKeyframes << " culled), ATE " << ate
            << " m, re-activated " << s.reactivatedPointsPerKeyframe << " and fused " << s.fusedPointsPerKeyframe
            << " per keyframe, " << s.mapMemoryMbPerKeyframe * 1024. << " KB per stored keyframe, "
            << reuse.points.size() << " map points (" << active << " active), " << reuse.edges.size() << " edges ("
            << covisibility << " co-visibility)" << std::endl;
  EXPECT_EQ(s.trackedFrames, kFrames);
  EXPECT_EQ(s.segments, 1u);
  EXPECT_LT(ate, 0.01);
  // Keyframes that left the window are kept, lean: well under the 0.5 MB each, while a window keyframe
  // (pyramid, images, patches) costs megabytes at 640x480 and still hundreds of KB here.
  EXPECT_GT(s.marginalizedKeyframes, 5u);
  EXPECT_LT(s.mapMemoryMbPerKeyframe, 0.5);
  const double windowMbPerKeyframe =
      (s.mapMemoryMb - s.marginalizedMemoryMb) / std::max(1u, s.keyframesHeld - s.marginalizedKeyframes);
  EXPECT_GT(windowMbPerKeyframe, 5. * s.mapMemoryMbPerKeyframe);
  // The second lap finds the first lap's points again.
  EXPECT_GT(s.reactivatedPointsPerKeyframe + s.fusedPointsPerKeyframe, 1.);
  // Every stored keyframe keeps its points (990 for 11 stored keyframes; 1000 in all was the bound before the first
  // frames after the initialisation got its velocity, which left fewer, better placed keyframes).
  EXPECT_GT(s.globalPoints, 80u * s.marginalizedKeyframes);
  // Points and graph are exposed: active and global points, co-visibility and pose-pose edges.
  EXPECT_GT(active, 100u);
  EXPECT_GT(reuse.points.size(), active + 1000u);
  EXPECT_GT(covisibility, 0u);
  EXPECT_GT(reuse.edges.size(), covisibility);

  // vo-strict keeps nothing of what leaves the window (one lap: more keyframes than the window holds).
  const TwoLapRun strict = runTwoLaps(scene, vpHSlamParameters::modeVoStrict, kFramesPerLap);
  EXPECT_GT(strict.run.statistics.keyframes, 8u);
  EXPECT_EQ(strict.run.statistics.marginalizedKeyframes, 0u);
  EXPECT_EQ(strict.run.statistics.globalPoints, 0u);
  EXPECT_TRUE(strict.edges.empty());
}

namespace
{
/*!
  Parameters of the half-turn runs. \e rotationPoints false drops new points whose depth the turn cannot measure (as
  DSO does, mapper.rotationFlowPx = 0): the window then empties during the turn, the scenario the seeding is for.
*/
vpHSlamParameters turnParameters(bool seed, bool rotationPoints = false)
{
  vpHSlamParameters params;
  params.system.deterministic = true;
  params.tracking.seedFromStoredMap = seed;
  if (!rotationPoints) {
    params.mapper.rotationFlowPx = 0.;
  }
  return params;
}

//! The half turn with \e params, its statistics and its Sim(3)-aligned ATE over every frame fed, printed.
struct TurnOutcome {
  vpHSlam::Statistics stats;
  double ate = 0.;
};

TurnOutcome runTurnAndPrint(const vpHSlamParameters &params, const char *what, double pivotBehind = 0.,
                            unsigned int framesAfterTurn = hslam_test::kHalfTurnFramesAfter)
{
  const hslam_test::HalfTurnRun r = hslam_test::runHalfTurn(params, pivotBehind, framesAfterTurn);
  TurnOutcome o{r.run.statistics, hslam_test::simAte(r.groundTruth, r.run.trajectory)};
  std::cout << "half turn in place in the second lap, " << what << ": " << o.stats.trackedFrames << " tracked, "
            << o.stats.lostFrames << " lost, " << o.stats.segments << " segment(s), "
            << o.stats.relocalizationsSucceeded << " relocalisation(s), ATE " << o.ate << " m" << std::endl;
  return o;
}
//! The turn held: every frame tracked, in one segment, and the whole run within \e maxAte.
void expectTrackedThrough(const TurnOutcome &o, double maxAte)
{
  EXPECT_EQ(o.stats.lostFrames, 0u);
  EXPECT_EQ(o.stats.segments, 1u);
  EXPECT_EQ(o.stats.trackedFrames, o.stats.frames);
  EXPECT_LT(o.ate, maxAte);
}
} // namespace

TEST(SystemGlobalMap, TurnInPlaceIsTrackedThroughWithPointsOnADepthPrior)
{
  // The defaults: while the camera turns, new points whose depth no baseline measures are kept on a weak prior at
  // the window's median depth, so the window never empties and no frame is lost (0 lost, ATE 0.073 m measured).
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  const vpHSlamParameters params = turnParameters(true, true);
  ASSERT_EQ(params.mapper.rotationFlowPx, vpHSlamParameters().mapper.rotationFlowPx);
  ASSERT_GT(params.mapper.rotationFlowPx, 0.);
  const TurnOutcome o = runTurnAndPrint(params, "points kept on a depth prior");
  expectTrackedThrough(o, 0.1);
}

TEST(SystemGlobalMap, HandHeldTurnIsTrackedThroughWithPointsOnADepthPrior)
{
  // A hand-held turn is not about the optical centre: here about an axis 10 cm behind it, so the camera moves 5 mm a
  // frame while turning 3 degrees. The translation flow between host and newest keyframe then reaches 1-2 px, and
  // with the gate at 1 px at this width (the first default) the points of the turn were refused as in DSO: 3 frames
  // lost, relocalised, ATE 0.24 m. With 2 px or more (the default: 4 px at 640): every frame tracked, ATE 0.009 m.
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  const TurnOutcome o = runTurnAndPrint(turnParameters(true, true), "hand-held (pivot 10 cm behind)", 0.1);
  expectTrackedThrough(o, 0.05);
}

TEST(SystemGlobalMap, HandHeldTurnAboutAWiderPivotIsFollowed)
{
  // The same turn about an axis 20 cm behind the camera (1 cm a frame). At 165 degrees a motion hypothesis whose
  // brightness collapsed at the coarsest level used to set the bound every other hypothesis then failed, so the
  // frame kept a pose 5 cm off and the arc was lost: ATE 0.21 m. With that level's RMSE not taken as a bound
  // (CoarseTracker::lowerHypothesisBound): every frame tracked, ATE 0.013 m measured.
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  const TurnOutcome o = runTurnAndPrint(turnParameters(true, true), "hand-held (pivot 20 cm behind)", 0.2);
  expectTrackedThrough(o, 0.05);
}

TEST(SystemGlobalMap, TurnInPlaceIsSeededAgainFromTheStoredMap)
{
  // Without the points on a depth prior the window empties in the turn. Bag-of-words + PnP finds the camera in the
  // first lap's stored keyframes after the turn, but no window point is left to confirm it against: without
  // seeding, the camera stays lost until a new segment starts (next test). Seeding the window from the stored map
  // keeps the one map.
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  vpHSlamParameters params = turnParameters(true);
  ASSERT_EQ(params.system.mode, vpHSlamParameters::modeSlam); // the defaults
  ASSERT_EQ(params.tracking.seedFromStoredMap, vpHSlamParameters().tracking.seedFromStoredMap);
  // With the window empty, when the camera is lost is a matter of chance. Since CoarseTracker::lowerHypothesisBound
  // (2026-11-29) it is lost at 165 degrees, facing what the first lap never saw, and the stored map can place it
  // again only from frame 347 (99 degrees on the way back), 32 frames later: longer than the default relocalisation
  // timeout (1 s). Before, it was lost on the way back (frame 356) and placed 2 frames later, ATE 0.070 m.
  params.tracking.relocalizationTimeout = 2.;
  // Measured with direct tracking, the default then. With adaptive tracking (the geometric term on every frame of the
  // turn) the window is seeded and the camera placed again all the same (1 segment, 2 relocalisations, 16 frames
  // lost), but the run ends at 0.21 m: the scale of the way back differs. Without points on a depth prior this
  // scenario is a lottery for either tracker (docs/hybrid-tracking.md, "Adaptive tracking").
  params.tracking.mode = vpHSlamParameters::trackingDirect;
  const TurnOutcome o = runTurnAndPrint(params, "seeded from the stored map");
  // One map: back as soon as the stored keyframes are in view (32 frames lost measured).
  EXPECT_EQ(o.stats.segments, 1u);
  EXPECT_GE(o.stats.relocalizationsSucceeded, 1u);
  EXPECT_LE(o.stats.lostFrames, 40u);
  // Every frame fed, the turn's included, Sim(3)-aligned: 0.111 m measured (0.117 m when the camera is not placed
  // again, with a 1 s timeout).
  EXPECT_LT(o.ate, 0.15);
}

TEST(SystemGlobalMap, TurnInPlaceWithoutSeedingStartsANewSegment)
{
  // The previous test's scenario holds: without seeding the camera is lost for the relocalisation timeout.
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  // The camera is lost in the turn, or soon after it (the window empties), and the new segment can only start once
  // the camera translates again: 120 frames of the lap after the turn leave it time to (with 60, a loss in the middle
  // of the turn left it initialising at the end of the run).
  const TurnOutcome o = runTurnAndPrint(turnParameters(false), "not seeded", 0., 120);
  EXPECT_GT(o.stats.lostFrames, 20u);
  EXPECT_EQ(o.stats.segments, 2u);
}
