// vpHSlam on bad input and misuse: clear exceptions, never a crash; an unused system reports nothing.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamException.h>

#include "system/RunStatistics.h"
#include "system/TrajectoryRecorder.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{
vpHSlamCamera smallCamera()
{
  vpHSlamCamera camera(vpHSlamCamera::pinhole, 160, 120, 150., 150., 79.5, 59.5);
  camera.setRectification(vpHSlamCamera::rectifyNone);
  return camera;
}

vpHSlamParameters deterministic()
{
  vpHSlamParameters params;
  params.system.deterministic = true;
  return params;
}
} // namespace

TEST(SystemInputs, WrongImageSizeIsAClearError)
{
  vpHSlam slam(smallCamera(), deterministic());
  vpImage<unsigned char> I(100, 100, 128);
  hslam_test::expectHSlamError([&]() { slam.track(I, 0.); }, vpHSlamException::invalidImage, {"100x100", "160x120"});
  EXPECT_EQ(slam.getStatistics().frames, 0u);
}

TEST(SystemInputs, LongInitialisationKeepsOnlyTheNewestFrames)
{
  // A camera that never initialises (a flat image): frames wait for the map, the oldest dropped past
  // initializer.maxFramesToInitialize. Under AddressSanitizer, LeakSanitizer checks that the dropped ones are freed
  // (ViSP 3.5's vpImage assignment leaked them when they were erased from a vector).
  vpHSlamParameters params = deterministic();
  params.initializer.maxFramesToInitialize = 5;
  vpHSlam slam(smallCamera(), params);
  vpImage<unsigned char> I(120, 160, 128);
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(slam.track(I, 0.1 * k), vpHSlam::stateInitializing);
  }
  EXPECT_EQ(slam.getStatistics().frames, 20u);
  EXPECT_EQ(slam.getStatistics().trackedFrames, 0u);
}

TEST(SystemInputs, EmptyImageIsAClearError)
{
  vpHSlam slam(smallCamera(), deterministic());
  vpImage<unsigned char> I;
  hslam_test::expectHSlamError([&]() { slam.track(I, 0.); }, vpHSlamException::invalidImage, {"0x0"});
}

TEST(SystemInputs, NonIncreasingTimestampIsAClearError)
{
  vpHSlam slam(smallCamera(), deterministic());
  vpImage<unsigned char> I(120, 160, 128);
  slam.track(I, 1.);
  hslam_test::expectHSlamError([&]() { slam.track(I, 1.); }, vpHSlamException::invalidTimestamps,
                               {"does not increase"});
}

TEST(SystemInputs, InvalidParametersAreRejected)
{
  vpHSlamParameters params = deterministic();
  params.mapper.windowSize = -3;
  EXPECT_THROW(vpHSlam(smallCamera(), params), vpHSlamException);
}

TEST(SystemInputs, NoFrameMeansNothingToReport)
{
  for (bool det : {true, false}) {
    vpHSlamParameters params;
    params.system.deterministic = det;
    vpHSlam slam(smallCamera(), params);
    slam.synchronize();
    EXPECT_EQ(slam.getState(), vpHSlam::stateInitializing);
    EXPECT_FALSE(slam.hasPose());
    EXPECT_TRUE(slam.getTrajectory().empty());
    EXPECT_TRUE(slam.getKeyframes().empty());
    EXPECT_TRUE(slam.getActivePoints().empty());
    const vpHSlam::Statistics s = slam.getStatistics();
    EXPECT_EQ(s.frames, 0u);
    EXPECT_EQ(s.trackedFrames, 0u);
    EXPECT_EQ(s.segments, 0u);
    EXPECT_EQ(s.trackingMsMedian, 0.);
    EXPECT_EQ(slam.getWidth(), 160u);
    EXPECT_EQ(slam.getHeight(), 120u);
  }
}

TEST(SystemInputs, TexturelessFramesNeverInitialiseNorCrash)
{
  vpHSlam slam(smallCamera(), deterministic());
  vpImage<unsigned char> I(120, 160, 90);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(slam.track(I, 0.1 * i), vpHSlam::stateInitializing);
  }
  EXPECT_EQ(slam.getStatistics().frames, 20u);
  EXPECT_EQ(slam.getStatistics().trackedFrames, 0u);
  slam.reset();
  EXPECT_EQ(slam.getStatistics().frames, 0u);
  EXPECT_NO_THROW(slam.track(I, 0.)); // timestamps start again after reset()
}

TEST(SystemInputs, FastPresetLoads)
{
  vpHSlamParameters params;
  params.load(std::string(HSLAM_SOURCE_DIR) + "/data/hslam-fast.yaml");
  EXPECT_NO_THROW(params.validate());
  EXPECT_EQ(params.features.desiredPointDensity, 600);
  EXPECT_EQ(params.mapper.windowSize, 6);
  EXPECT_EQ(params.mapper.maxOptimizationIterations, 3);
  EXPECT_EQ(params.tracker.huberThreshold, vpHSlamParameters().tracker.huberThreshold); // others keep defaults
}

TEST(SystemParts, PercentileIsNearestRank)
{
  EXPECT_EQ(hslam::percentile({}, 0.5), 0.);
  EXPECT_EQ(hslam::percentile({3., 1., 2.}, 0.5), 2.);
  EXPECT_EQ(hslam::percentile({1., 2., 3., 4.}, 0.5), 2.);
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) {
    v.push_back(i);
  }
  EXPECT_EQ(hslam::percentile(v, 0.95), 95.);
  EXPECT_EQ(hslam::percentile(v, 1.), 100.);
}

TEST(SystemParts, PeakMemoryIsReadFromProc)
{
  // Current first: the high-water mark read afterwards includes it (the reads themselves allocate a little).
  const double now = hslam::processMemoryMb("VmRSS:");
  const double peak = hslam::processMemoryMb("VmHWM:");
  EXPECT_GT(peak, 1.);
  EXPECT_GE(peak + 1e-9, now);
  EXPECT_EQ(hslam::processMemoryMb("NoSuchField:"), 0.);
}

TEST(SystemParts, TrajectoryFollowsKeyframeCorrections)
{
  hslam::TrajectoryRecorder recorder;
  const Eigen::Quaterniond qY(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()));
  const hslam::SE3d wMk0(qY, Eigen::Vector3d(1., 0., 0.));
  recorder.addKeyframe(0, 0, 0., wMk0, 0);
  recorder.addFrame(0, 0., 0, hslam::SE3d(), 0);
  const hslam::SE3d k0Mc(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0., 0., 0.5));
  recorder.addFrame(2, 0.2, 0, k0Mc, 0);
  recorder.addFrame(1, 0.1, 0, hslam::SE3d(), 0); // recorded late (e.g. tracked backwards)
  vpHSlamTrajectory traj = recorder.trajectory();
  ASSERT_EQ(traj.size(), 3u);
  EXPECT_TRUE(traj.isSorted());
  EXPECT_NEAR(traj.get_wMc(2)[0][3], 1. + 0.5 * std::sin(0.1), 1e-12);
  // The keyframe moves: the frame tracked against it moves with it.
  const hslam::SE3d wMk0new(qY, Eigen::Vector3d(2., 0., 0.));
  recorder.updateKeyframe(0, wMk0new);
  traj = recorder.trajectory();
  EXPECT_NEAR(traj.get_wMc(2)[0][3], 2. + 0.5 * std::sin(0.1), 1e-12);
  EXPECT_NEAR(traj.get_wMc(2)[2][3], 0.5 * std::cos(0.1), 1e-12);
  hslam::SE3d last;
  ASSERT_TRUE(recorder.lastFramePose(last));
  EXPECT_NEAR(last.translation().x(), 2. + 0.5 * std::sin(0.1), 1e-12);
  hslam_test::expectHSlamError([&]() { recorder.addKeyframe(5, 3, 0.3, wMk0, 0); }, vpHSlamException::invalidArgument,
                               {"keyframe id 5"});
}

TEST(SystemParts, TrajectoryFollowsALoopCorrectionWithScale)
{
  // A loop correction moves keyframe 0 and divides its map by 2: a frame 0.5 m in front of it ends 0.25 m in front
  // of its new pose; frames on other keyframes do not move.
  hslam::TrajectoryRecorder recorder;
  recorder.addKeyframe(0, 0, 0., hslam::SE3d(), 0);
  recorder.addKeyframe(1, 5, 0.5, hslam::SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(3., 0., 0.)), 0);
  recorder.addFrame(1, 0.1, 0, hslam::SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0., 0., 0.5)), 0);
  recorder.addFrame(6, 0.6, 1, hslam::SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0., 0., 0.5)), 0);
  const hslam::SE3d wMk0(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1., 0., 0.));
  recorder.correctKeyframes({0}, {wMk0}, {2.});
  hslam::SE3d w1, w6;
  ASSERT_TRUE(recorder.framePose(1, w1));
  ASSERT_TRUE(recorder.framePose(6, w6));
  EXPECT_NEAR((w1.translation() - Eigen::Vector3d(1., 0., 0.25)).norm(), 0., 1e-12);
  EXPECT_NEAR((w6.translation() - Eigen::Vector3d(3., 0., 0.5)).norm(), 0., 1e-12);
  EXPECT_NEAR((recorder.keyframePose(0).translation() - Eigen::Vector3d(1., 0., 0.)).norm(), 0., 1e-12);
}
