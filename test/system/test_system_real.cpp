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

//! \e frames of \e folder (0: all) with frames coverBegin-coverEnd replaced by black images (a covered lens).
hslam_test::SystemRun runCovered(const std::string &folder, unsigned int frames, const vpHSlamParameters &params,
                                 unsigned int coverBegin, unsigned int coverEnd)
{
  return hslam_test::runSource(folder, frames, params,
                               [&](const vpHSlamImageSource::Frame &f, vpImage<unsigned char> &I) {
                                 if (f.index >= coverBegin && f.index <= coverEnd) {
                                   I = vpImage<unsigned char>(I.getHeight(), I.getWidth(), 0);
                                 }
                               });
}

//! Frames after \e coverEnd until the first tracked one (-1: never); states[i] is frame i's.
int framesUntilTracked(const std::vector<vpHSlam::State> &states, unsigned int coverEnd)
{
  for (size_t i = coverEnd + 1; i < states.size(); ++i) {
    if (states[i] == vpHSlam::stateTracking) {
      return static_cast<int>(i - coverEnd - 1);
    }
  }
  return -1;
}

//! A whole shared sequence run with and without frames coverBegin-coverEnd black, and what the cover tests check.
struct CoverComparison {
  hslam_test::SystemRun plain, covered;
  double ate = 0., atePlain = 0.; //!< Sim(3) ATE of each run, ground-truth units
  int firstTrackedAfter = -1;     //!< frames after the cover until the first tracked one (-1: never)
};

//! The defaults in deterministic mode with \e budget candidate points per keyframe.
vpHSlamParameters deterministicWithBudget(int budget)
{
  vpHSlamParameters params;
  params.system.deterministic = true;
  params.features.desiredImmatureDensity = budget;
  return params;
}

CoverComparison compareCover(const std::string &folder, const std::string &groundtruth, const vpHSlamParameters &params,
                             unsigned int coverBegin, unsigned int coverEnd)
{
  CoverComparison c;
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(folder + "/" + groundtruth);
  c.plain = hslam_test::runSource(folder, 0, params);
  c.covered = runCovered(folder, 0, params, coverBegin, coverEnd);
  c.ate = hslam_test::simAte(gt, c.covered.trajectory);
  c.atePlain = hslam_test::simAte(gt, c.plain.trajectory);
  c.firstTrackedAfter = framesUntilTracked(c.covered.states, coverEnd);
  return c;
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

/*!
  Issue 8's covered lens on 7-Scenes: frames coverBegin-coverEnd black, slam mode with direct tracking (frames are
  described only while lost). The camera must be found again in the same map within 10 frames of the images returning,
  and the run must stay about as accurate as without the cover. Two point budgets: the relocalised pose's
  confirmation (tracking.relocalizationCheckInliers) once refused 4 of 5 budgets after a 6-frame cover (480 and 520
  among them) while accepting 500.
*/
void expectSevenScenesCoverRelocalised(unsigned int frames, unsigned int coverBegin, unsigned int coverEnd)
{
  HSLAM_REQUIRE_SHARED_DATA(folder, "7scenes_redkitchen_000-299");
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(folder + "/groundtruth.txt");
  for (int budget : {480, 520}) {
    vpHSlamParameters params = fastPreset();
    params.system.mode = vpHSlamParameters::modeSlam;
    params.features.desiredImmatureDensity = budget;
    params.tracking.mode = vpHSlamParameters::trackingDirect; // what this test is about
    const hslam_test::SystemRun plain = hslam_test::runSource(folder, frames, params);
    const hslam_test::SystemRun covered = runCovered(folder, frames, params, coverBegin, coverEnd);
    const int firstTrackedAfter = framesUntilTracked(covered.states, coverEnd);
    const vpHSlam::Statistics &stats = covered.statistics;
    const double atePlain = hslam_test::simAte(gt, plain.trajectory);
    const double ateCovered = hslam_test::simAte(gt, covered.trajectory);
    std::cout << "7-Scenes first " << frames << " frames, frames " << coverBegin << "-" << coverEnd << " black, budget "
              << budget << ": segments " << stats.segments << ", relocalisations " << stats.relocalizationsSucceeded
              << "/" << stats.relocalizationsAttempted << ", tracked " << stats.trackedFrames << ", back after "
              << firstTrackedAfter << " frames, ATE " << ateCovered << " m (without the cover " << atePlain << " m)"
              << std::endl;
    EXPECT_EQ(plain.statistics.segments, 1u);
    EXPECT_EQ(stats.segments, 1u) << "relocalised in the same map, no new segment (budget " << budget << ")";
    EXPECT_GE(stats.relocalizationsSucceeded, 1u);
    ASSERT_GE(firstTrackedAfter, 0);
    EXPECT_LE(firstTrackedAfter, 10) << "tracking back within 10 frames of the images returning";
    ASSERT_FALSE(covered.states.empty());
    EXPECT_EQ(covered.states.back(), vpHSlam::stateTracking);
    EXPECT_LE(ateCovered, 1.5 * atePlain);
  }
}

TEST(SystemReal, SevenScenesCoveredLensIsRelocalisedInSlamMode)
{
  // Six black frames: the camera is still near its last pose.
  expectSevenScenesCoverRelocalised(180, 120, 125);
}

TEST(SystemReal, SevenScenesLongCoverIsRelocalisedOnTheWindowsTriangulatedPoints)
{
  // The 41 black frames: the camera comes back 0.26 m and 10 degrees away (ground truth), where the window's
  // corners match too little; the ORB points triangulated between the window's keyframes place it
  // (tracking.relocalizeInWindow).
  expectSevenScenesCoverRelocalised(220, 120, 160);
}

TEST(SystemReal, SevenScenesEarlyCoverKeepsTheFramesTrackedBeforeIt)
{
  // Frames 60-100 black, three keyframes after the initialisation: the first keyframe after the relocalisation comes
  // from 0.2 m away and fits the window with an RMSE above the bound of DSO's initialisation check. The check took it
  // for a wrong initialisation and discarded the segment, the 63 frames tracked before the cover with it (defaults,
  // budgets 485, 510 and 515 of 11 tried; two are run here). A confirmed relocalisation now ends the check for the
  // segment.
  HSLAM_REQUIRE_SHARED_DATA(folder, "7scenes_redkitchen_000-299");
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(folder + "/groundtruth.txt");
  const unsigned int frames = 160, coverBegin = 60, coverEnd = 100;
  for (int budget : {485, 515}) {
    vpHSlamParameters params;
    params.system.deterministic = true;
    params.features.desiredImmatureDensity = budget;
    ASSERT_EQ(params.system.mode, vpHSlamParameters::modeSlam);
    params.tracking.mode = vpHSlamParameters::trackingDirect; // the scenario as measured (before adaptive tracking)
    const hslam_test::SystemRun plain = hslam_test::runSource(folder, frames, params);
    const hslam_test::SystemRun covered = runCovered(folder, frames, params, coverBegin, coverEnd);
    ASSERT_GT(covered.states.size(), static_cast<size_t>(coverBegin));
    size_t trackedBefore = 0;
    for (size_t i = 0; i < coverBegin; ++i) {
      trackedBefore += covered.states[i] == vpHSlam::stateTracking ? 1 : 0;
    }
    // The trajectory is sorted by time: the poses before the cover are its first entries. Frame i's timestamp is
    // the plain run's i-th (both runs read the same frames).
    ASSERT_EQ(plain.trajectory.getTimestamps().size(), static_cast<size_t>(frames)) << "every frame has a pose";
    const double lastBefore = plain.trajectory.getTimestamps().at(coverBegin - 1);
    size_t keptBefore = 0;
    for (double t : covered.trajectory.getTimestamps()) {
      keptBefore += t <= lastBefore ? 1 : 0;
    }
    const double atePlain = hslam_test::simAte(gt, plain.trajectory);
    const double ateCovered = hslam_test::simAte(gt, covered.trajectory);
    std::cout << "7-Scenes first " << frames << " frames, frames " << coverBegin << "-" << coverEnd << " black, budget "
              << budget << ": segments " << covered.statistics.segments << ", tracked "
              << covered.statistics.trackedFrames << ", poses before the cover " << keptBefore << " (" << trackedBefore
              << " tracked), ATE " << ateCovered << " m (without the cover " << atePlain << " m)" << std::endl;
    EXPECT_EQ(plain.statistics.segments, 1u);
    EXPECT_EQ(covered.statistics.segments, 1u);
    EXPECT_GE(trackedBefore, 25u); // 0-30 initialise (tracked backwards afterwards)
    EXPECT_GE(keptBefore, trackedBefore) << "frames tracked before the cover are kept (budget " << budget << ")";
    ASSERT_FALSE(covered.states.empty());
    EXPECT_EQ(covered.states.back(), vpHSlam::stateTracking);
    EXPECT_LE(ateCovered, 1.5 * atePlain);
  }
}

TEST(SystemReal, KittiCoverIsBridgedByTheMotionTheCarKept)
{
  // Frames 25-34 black: the car drives on about 8 m. Nothing the window holds matches 15 ORB inliers when the images
  // return (4-7), and a new segment started (another scale, ATE 6.6 m over the run). The alignment from the motion
  // continued over the lost frames ends within 0.06 of a step of it and is taken (see tracking/MotionContinuation.h),
  // and the next frame starts from that motion.
  HSLAM_REQUIRE_SHARED_DATA(folder, "kitti06_000-050");
  const unsigned int coverBegin = 25, coverEnd = 34;
  for (int budget : {490, 510}) {
    const CoverComparison c =
        compareCover(folder, "groundtruth_tum.txt", deterministicWithBudget(budget), coverBegin, coverEnd);
    const hslam_test::SystemRun &covered = c.covered;
    size_t trackedAfter = 0;
    for (size_t i = coverEnd + 1; i < covered.states.size(); ++i) {
      trackedAfter += covered.states[i] == vpHSlam::stateTracking ? 1 : 0;
    }
    const vpHSlam::Statistics &stats = covered.statistics;
    std::cout << "KITTI 06 0-50, frames " << coverBegin << "-" << coverEnd << " black, budget " << budget
              << ": segments " << stats.segments << ", relocalisations " << stats.relocalizationsSucceeded << "/"
              << stats.relocalizationsAttempted << ", back after " << c.firstTrackedAfter << " frames, " << trackedAfter
              << " of " << covered.states.size() - coverEnd - 1 << " tracked after, ATE " << c.ate
              << " m (without the cover " << c.atePlain << " m)" << std::endl;
    EXPECT_EQ(stats.segments, 1u) << "budget " << budget;
    EXPECT_GE(stats.relocalizationsSucceeded, 1u);
    EXPECT_EQ(c.firstTrackedAfter, 0) << "the first frame after the cover is placed";
    EXPECT_EQ(trackedAfter, covered.states.size() - coverEnd - 1);
    EXPECT_LE(c.ate, 1.5 * c.atePlain); // 0.020 / 0.021 m measured; 0.25 m for one of 21 covers before the motion
                                        // was kept for the frame after the relocalisation
  }
}

TEST(SystemReal, TsukubaCoverIsNotRelocalisedOnARepeatedTexture)
{
  // Frames 50-69 black: the camera comes back 0.6 m and 20 degrees away. With budget 485 the window's triangulated
  // points gave a PnP pose about 10 degrees off (a repeated texture), the alignment stayed on it and the run went on in
  // one segment at 8 cm ATE (0.3 cm without the cover). Its alignment left 54 % of the reference's residuals below the
  // cutoff, right ones 71-92 % (tracking.relocalizationMinInlierRatio): the pose is refused and the next frame is
  // placed right. Budget 495 was placed right before and stays so.
  HSLAM_REQUIRE_SHARED_DATA(folder, "tsukuba_cg_000-149");
  const unsigned int coverBegin = 50, coverEnd = 69;
  for (int budget : {485, 495}) {
    const CoverComparison c =
        compareCover(folder, "groundtruth.txt", deterministicWithBudget(budget), coverBegin, coverEnd);
    const vpHSlam::Statistics &stats = c.covered.statistics;
    std::cout << "Tsukuba, frames " << coverBegin << "-" << coverEnd << " black, budget " << budget << ": segments "
              << stats.segments << ", relocalisations " << stats.relocalizationsSucceeded << "/"
              << stats.relocalizationsAttempted << ", back after " << c.firstTrackedAfter << " frames, ATE " << c.ate
              << " cm (without the cover " << c.atePlain << " cm)" << std::endl;
    EXPECT_EQ(stats.segments, 1u) << "budget " << budget;
    EXPECT_GE(stats.relocalizationsSucceeded, 1u);
    ASSERT_GE(c.firstTrackedAfter, 0);
    EXPECT_LE(c.firstTrackedAfter, 10);
    EXPECT_LE(c.ate, 2. * c.atePlain) << "budget " << budget; // 0.38 / 0.37 cm measured; 7.97 cm for 485 before
  }
}

TEST(SystemReal, KittiCarFoundAgainKeepsItsMotionAndRenewsItsWindow)
{
  // Two ways a car found again after a cover drifted afterwards (KITTI 06, 1.2 m a frame):
  // - found by its continued motion (frames 30-39 black, direct tracking): the window's keyframes are 10 m behind, the
  //   points it still tracks are distant, and the next keyframe came 9 frames later; 0.12 m and 0.69 m ATE at budgets
  //   475 and 525. The relocalised frame and the next two are now keyframes.
  // - found by the window's points (frames 35-39 black, hybrid tracking, budget 505): the frame after started from no
  //   motion and was placed 0.4 m on; 0.117 m ATE. The motion is now kept when the pose found is where it continued.
  HSLAM_REQUIRE_SHARED_DATA(folder, "kitti06_000-050");
  struct Case {
    unsigned int coverBegin, coverEnd;
    int budget;
    vpHSlamParameters::TrackingMode mode;
  };
  for (const Case &c :
       {Case{30, 39, 475, vpHSlamParameters::trackingDirect}, Case{30, 39, 525, vpHSlamParameters::trackingDirect},
        Case{35, 39, 505, vpHSlamParameters::trackingHybrid}}) {
    vpHSlamParameters params = deterministicWithBudget(c.budget);
    params.tracking.mode = c.mode;
    const CoverComparison r = compareCover(folder, "groundtruth_tum.txt", params, c.coverBegin, c.coverEnd);
    std::cout << "KITTI 06 0-50, frames " << c.coverBegin << "-" << c.coverEnd << " black, budget " << c.budget
              << (c.mode == vpHSlamParameters::trackingHybrid ? ", hybrid" : ", direct") << ": segments "
              << r.covered.statistics.segments << ", relocalisations " << r.covered.statistics.relocalizationsSucceeded
              << ", back after " << r.firstTrackedAfter << " frames, ATE " << r.ate << " m (without the cover "
              << r.atePlain << " m)" << std::endl;
    EXPECT_EQ(r.covered.statistics.segments, 1u);
    EXPECT_EQ(r.firstTrackedAfter, 0) << "the first frame after the cover is placed";
    EXPECT_LE(r.ate, 2. * r.atePlain) << "budget " << c.budget; // before: 5.4x, 31x and 4.5x
  }
}
