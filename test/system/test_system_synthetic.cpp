// System tests on a synthetic sequence with exact ground truth (vpHSlamSyntheticScene, 640x480, 100 frames):
// accuracy, determinism, real-time mode, lost-tracking recovery.
#include "HSlamTestData.h"
#include "SystemTestUtils.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

namespace
{
constexpr unsigned int kWidth = 640, kHeight = 480, kFrames = 100, kSeed = 3;

#define HSLAM_REQUIRE_SYNTHETIC(dir)                                                                                   \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";                \
  }                                                                                                                    \
  const std::string dir = hslam_test::syntheticSequence(kWidth, kHeight, kFrames, kSeed);

vpHSlamParameters parameters(bool deterministic)
{
  vpHSlamParameters params;
  params.system.deterministic = deterministic;
  return params;
}

size_t countState(const std::vector<vpHSlam::State> &states, vpHSlam::State s)
{
  return static_cast<size_t>(std::count(states.begin(), states.end(), s));
}
} // namespace

TEST(SystemSynthetic, TracksWholeSequenceAccurately)
{
  HSLAM_REQUIRE_SYNTHETIC(dir);
  const hslam_test::SystemRun run = hslam_test::runSource(dir, 0, parameters(true));
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(dir + "/groundtruth.txt");
  const double ate = hslam_test::simAte(gt, run.trajectory);
  const double length = hslam_test::pathLength(gt);
  std::cout << "synthetic: tracked " << run.statistics.trackedFrames << "/" << kFrames << ", keyframes "
            << run.statistics.keyframes << ", ATE " << ate << " m over a path of " << length << " m" << std::endl;
  EXPECT_EQ(run.statistics.frames, kFrames);
  EXPECT_GE(run.statistics.trackedFrames, kFrames - 2); // from the first frames (earlier ones tracked backwards)
  EXPECT_EQ(run.statistics.segments, 1u);
  EXPECT_GE(run.statistics.keyframes, 4u);
  EXPECT_LT(ate, 0.002); // metres, exact images: measured 0.4 mm
  EXPECT_EQ(run.trajectory.size(), run.statistics.trackedFrames);
  EXPECT_TRUE(run.trajectory.isSorted());
  for (const vpHSlam::Keyframe &k : run.keyframes) {
    EXPECT_EQ(k.segment, 0u);
  }
}

TEST(SystemSynthetic, DeterministicModeIsBitIdentical)
{
  HSLAM_REQUIRE_SYNTHETIC(dir);
  const hslam_test::SystemRun a = hslam_test::runSource(dir, 60, parameters(true));
  const hslam_test::SystemRun b = hslam_test::runSource(dir, 60, parameters(true));
  ASSERT_GT(a.trajectory.size(), 50u);
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (size_t i = 0; i < a.trajectory.size(); ++i) {
    ASSERT_EQ(a.trajectory.getTimestamp(i), b.trajectory.getTimestamp(i));
    for (unsigned int r = 0; r < 3; ++r) {
      for (unsigned int c = 0; c < 4; ++c) {
        ASSERT_EQ(a.trajectory.get_wMc(i)[r][c], b.trajectory.get_wMc(i)[r][c]) << "pose " << i;
      }
    }
  }
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  EXPECT_EQ(a.statistics.activePoints, b.statistics.activePoints);
}

TEST(SystemSynthetic, RealTimeModeTracksEveryFrame)
{
  HSLAM_REQUIRE_SYNTHETIC(dir);
  const hslam_test::SystemRun run = hslam_test::runSource(dir, 0, parameters(false));
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(dir + "/groundtruth.txt");
  const double ate = hslam_test::simAte(gt, run.trajectory);
  std::cout << "real time: tracked " << run.statistics.trackedFrames << ", keyframes " << run.statistics.keyframes
            << ", skipped for mapping " << run.statistics.mappingSkippedFrames << ", ATE " << ate << " m" << std::endl;
  // Frames come faster than mapping consumes them here: mapping skips some, tracking none.
  EXPECT_EQ(countState(run.states, vpHSlam::stateLost), 0u);
  EXPECT_GE(run.statistics.trackedFrames, kFrames - 2);
  EXPECT_GE(run.statistics.keyframes, 2u);
  EXPECT_LT(ate, 0.01);
}

TEST(SystemSynthetic, RecoversFromLostTrackingWithANewSegment)
{
  HSLAM_REQUIRE_SYNTHETIC(dir);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  vpHSlamParameters params = parameters(true);
  params.tracking.relocalize = false; // the fallback: a loss starts a new segment (relocalisation: next test)
  vpHSlam slam(*source, params);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  std::vector<vpHSlam::State> before, blind, after;
  const double dt = 1. / 30.;
  double t = 0.;
  while (source->acquire(I, frame)) {
    if (frame.index == 40) {
      // A covered lens: uniform frames cannot be aligned.
      const vpImage<unsigned char> black(I.getHeight(), I.getWidth(), 0);
      for (int i = 0; i < 6; ++i, t += dt) {
        blind.push_back(slam.track(black, t));
      }
    }
    (frame.index < 40 ? before : after).push_back(slam.track(I, t));
    t += dt;
  }
  ASSERT_EQ(before.back(), vpHSlam::stateTracking);
  EXPECT_GE(countState(blind, vpHSlam::stateLost), 1u);
  EXPECT_EQ(after.back(), vpHSlam::stateTracking);
  const vpHSlam::Statistics stats = slam.getStatistics();
  EXPECT_EQ(stats.segments, 2u);
  EXPECT_GE(stats.lostFrames, 1u);
  EXPECT_GT(slam.getTrajectory(0).size(), 35u); // the old segment is kept
  EXPECT_GT(slam.getTrajectory(1).size(), 30u);
  EXPECT_EQ(slam.getTrajectory().size(), slam.getTrajectory(0).size() + slam.getTrajectory(1).size());
  const std::vector<unsigned int> segments = slam.getTrajectorySegments();
  EXPECT_EQ(segments.size(), slam.getTrajectory().size());
  const std::vector<vpHSlam::Keyframe> keyframes = slam.getKeyframes();
  ASSERT_GE(keyframes.size(), 4u);
  EXPECT_EQ(keyframes.front().segment, 0u);
  EXPECT_EQ(keyframes.back().segment, 1u);
  EXPECT_FALSE(keyframes.front().inWindow);
  EXPECT_TRUE(keyframes.back().inWindow);
}

namespace
{
/*!
  The covered lens of the previous test with relocalisation on: the frames after it are matched to the keyframes seen
  before (BoW, ORB, PnP) and tracking resumes in the same map and segment.
*/
void expectCoveredLensRelocalised(const vpHSlamParameters &params)
{
  HSLAM_REQUIRE_SYNTHETIC(dir);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  ASSERT_TRUE(params.tracking.relocalize);
  vpHSlam slam(*source, params);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  std::vector<vpHSlam::State> after;
  const double dt = 1. / 30.;
  double t = 0.;
  int firstTrackedAfter = -1;
  while (source->acquire(I, frame)) {
    if (frame.index == 40) {
      const vpImage<unsigned char> black(I.getHeight(), I.getWidth(), 0);
      for (int i = 0; i < 10; ++i, t += dt) {
        slam.track(black, t);
      }
    }
    const vpHSlam::State state = slam.track(I, t);
    if (frame.index >= 40) {
      after.push_back(state);
      if (state == vpHSlam::stateTracking && firstTrackedAfter < 0) {
        firstTrackedAfter = static_cast<int>(frame.index) - 40;
      }
    }
    t += dt;
  }
  const vpHSlam::Statistics stats = slam.getStatistics();
  EXPECT_EQ(stats.segments, 1u) << "relocalised in the same map, no new segment";
  EXPECT_GE(stats.relocalizationsAttempted, 1u);
  EXPECT_EQ(stats.relocalizationsSucceeded, 1u);
  ASSERT_GE(firstTrackedAfter, 0);
  EXPECT_LE(firstTrackedAfter, 10) << "tracking back within 10 frames of the images returning";
  EXPECT_EQ(after.back(), vpHSlam::stateTracking);
  EXPECT_GE(stats.lostFrames, 1u);
}
} // namespace

TEST(SystemSynthetic, CoveredLensIsRelocalisedInTheSameMap)
{
  vpHSlamParameters params = parameters(true);
  params.tracking.mode = vpHSlamParameters::trackingHybrid; // every frame described
  expectCoveredLensRelocalised(params);
}

TEST(SystemSynthetic, CoveredLensIsRelocalisedWithDirectTrackingInSlamMode)
{
  // Direct tracking describes no frame while it tracks; in slam mode (keyframes indexed for loop detection) a lost
  // camera's frames are described and relocalised all the same.
  vpHSlamParameters params = parameters(true);
  params.system.mode = vpHSlamParameters::modeSlam;
  params.tracking.mode = vpHSlamParameters::trackingDirect; // what this test is about
  expectCoveredLensRelocalised(params);
}

TEST(SystemSynthetic, CoveredLensIsRelocalisedWithDirectTrackingInVoReuseMode)
{
  // vo-reuse keeps a global map too, so its keyframes are indexed and a lost camera is found in them (before
  // 2026-11-29 only slam mode did this: vo-reuse started a new segment, whose initialisation can take seconds).
  vpHSlamParameters params = parameters(true);
  params.system.mode = vpHSlamParameters::modeVoReuse;
  params.tracking.mode = vpHSlamParameters::trackingDirect; // what this test is about
  expectCoveredLensRelocalised(params);
}

TEST(SystemSynthetic, RealTimeHybridCoveredLensKeepsTracking)
{
  // The same covered lens in real-time mode (mapping thread; relocalisation waits for it): run under
  // ThreadSanitizer in CI. The outcome depends on scheduling, so only what must always hold is checked: every
  // frame processed, tracking at the end, at most one new segment, counters consistent. The run stops at frame
  // 70, 30 frames after the images return: the rest adds nothing here and costs minutes under ThreadSanitizer.
  HSLAM_REQUIRE_SYNTHETIC(dir);
  constexpr unsigned int kLastFrame = 70;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  vpHSlamParameters params = parameters(false);
  params.tracking.mode = vpHSlamParameters::trackingHybrid;
  vpHSlam slam(*source, params);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  const double dt = 1. / 30.;
  double t = 0.;
  unsigned int fed = 0;
  vpHSlam::State last = vpHSlam::stateInitializing;
  while (source->acquire(I, frame) && frame.index <= kLastFrame) {
    if (frame.index == 40) {
      const vpImage<unsigned char> black(I.getHeight(), I.getWidth(), 0);
      for (int i = 0; i < 10; ++i, t += dt, ++fed) {
        slam.track(black, t);
      }
    }
    last = slam.track(I, t);
    t += dt;
    ++fed;
  }
  slam.synchronize();
  const vpHSlam::Statistics stats = slam.getStatistics();
  EXPECT_EQ(stats.frames, fed);
  EXPECT_EQ(last, vpHSlam::stateTracking);
  EXPECT_LE(stats.segments, 2u);
  EXPECT_LE(stats.relocalizationsSucceeded, stats.relocalizationsAttempted);
  EXPECT_EQ(slam.getTrajectory().size(), stats.trackedFrames);
}
