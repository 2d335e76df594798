// System tests on a SHORTENED real sequence of ../shared/data (skipped when absent): deterministic run,
// bounds on the tracked share and on the Sim(3)-aligned ATE against the ground truth.
#include "HSlamTestData.h"
#include "SystemTestUtils.h"

#include <gtest/gtest.h>

#include <iostream>

TEST(SystemReal, SevenScenesFirst100Frames)
{
  HSLAM_REQUIRE_SHARED_DATA(folder, "7scenes_redkitchen_000-299");
  vpHSlamParameters params;
  params.system.deterministic = true;
  const unsigned int frames = 100;
  const hslam_test::SystemRun run = hslam_test::runSource(folder, frames, params);
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(folder + "/groundtruth.txt");
  const double ate = hslam_test::simAte(gt, run.trajectory);
  std::cout << "7-Scenes first " << frames << " frames: tracked " << run.statistics.trackedFrames << ", keyframes "
            << run.statistics.keyframes << ", ATE " << ate << " m, tracking " << run.statistics.trackingMsMedian
            << " ms median" << std::endl;
  EXPECT_EQ(run.statistics.frames, frames);
  EXPECT_GE(run.statistics.trackedFrames, 95u); // the whole sequence from the first frames
  EXPECT_EQ(run.statistics.segments, 1u);
  EXPECT_LT(ate, 0.05); // metres; DSO on the full 300 frames: 0.183 m
}

namespace
{
vpHSlamParameters fastPreset()
{
  vpHSlamParameters params;
  params.load(std::string(HSLAM_SOURCE_DIR) + "/data/hslam-fast.yaml");
  params.system.deterministic = true;
  return params;
}
} // namespace

TEST(SystemReal, KittiWholeSequenceFastPreset)
{
  HSLAM_REQUIRE_SHARED_DATA(folder, "kitti06_000-050");
  const hslam_test::SystemRun run = hslam_test::runSource(folder, 0, fastPreset());
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(folder + "/groundtruth_tum.txt");
  const double ate = hslam_test::simAte(gt, run.trajectory);
  std::cout << "KITTI 06 0-50: tracked " << run.statistics.trackedFrames << ", keyframes " << run.statistics.keyframes
            << ", ATE " << ate << " m" << std::endl;
  // DSO, LDSO and ORB-SLAM2 do not initialise on these 51 frames (fast forward motion at 10 Hz).
  EXPECT_GE(run.statistics.trackedFrames, 50u);
  EXPECT_EQ(run.statistics.segments, 1u);
  EXPECT_LT(ate, 0.1); // metres over ~50 m of road; measured 0.02
}

TEST(SystemReal, TsukubaFirst75FramesFastPreset)
{
  HSLAM_REQUIRE_SHARED_DATA(folder, "tsukuba_cg_000-149");
  const unsigned int frames = 75;
  const hslam_test::SystemRun run = hslam_test::runSource(folder, frames, fastPreset());
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(folder + "/groundtruth.txt");
  const double ate = hslam_test::simAte(gt, run.trajectory);
  std::cout << "Tsukuba first " << frames << " frames: tracked " << run.statistics.trackedFrames << ", keyframes "
            << run.statistics.keyframes << ", ATE " << ate << " cm" << std::endl;
  EXPECT_GE(run.statistics.trackedFrames, frames - 2);
  EXPECT_EQ(run.statistics.segments, 1u);
  EXPECT_LT(ate, 2.); // centimetres (Tsukuba units); DSO on 150 frames: 24 cm
}
