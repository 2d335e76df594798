// Loop closure (issue 10) through vpHSlam: the synthetic room filmed wall after wall twice (look-outward loop,
// 2 laps of 400 frames, 320x240, noise, motion blur, exposure changes, vignette, response), fast preset, direct
// tracking. A sliding window cannot close this loop by itself (what it saw first has left it): vo-strict drifts,
// slam must detect the revisit, verify it, correct the old side and end more accurate; and the shared real
// sequences, which have no loop, must give none.
#include "HSlamTestData.h"
#include "SystemTestUtils.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <memory>
#include <thread>
#include <vector>

namespace
{
constexpr unsigned int kWidth = 320, kHeight = 240, kLaps = 2, kFramesPerLap = 400, kSeed = 1;
constexpr unsigned int kFrames = kLaps * kFramesPerLap + 1;

vpHSlamParameters fastPreset(vpHSlamParameters::Mode mode)
{
  vpHSlamParameters params;
  params.load(std::string(HSLAM_SOURCE_DIR) + "/data/hslam-fast.yaml");
  params.system.deterministic = true;
  params.system.mode = mode;
  return params;
}

//! The look-outward room, 2 laps, with noise, motion blur, exposure changes, vignette and response (made once).
std::string outwardLoop()
{
  vpHSlamSyntheticScene::Effects effects;
  effects.noiseSigma = 4.;
  effects.motionBlur = effects.exposureChanges = effects.vignette = effects.response = true;
  return hslam_test::syntheticSequence(kWidth, kHeight, kFrames, kSeed, kLaps, true, effects);
}
} // namespace

TEST(SystemLoop, OutwardLoopIsClosedAndBeatsOdometry)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  const std::string dir = outwardLoop();
  const vpHSlamTrajectory gt = vpHSlamTrajectory::readTum(dir + "/groundtruth.txt");
  // One deterministic run says little (a 2 % change of the point budget moves it a lot, and about one run in five
  // loses the scale before the revisit, slam or not): five budgets, compared by their medians.
  std::vector<double> slamAte, strictAte;
  int runsWithLoop = 0;
  for (int budget : {480, 490, 500, 510, 520}) {
    vpHSlamParameters slamParams = fastPreset(vpHSlamParameters::modeSlam);
    vpHSlamParameters strictParams = fastPreset(vpHSlamParameters::modeVoStrict);
    slamParams.features.desiredImmatureDensity = strictParams.features.desiredImmatureDensity = budget;
    const hslam_test::SystemRun slam = hslam_test::runSource(dir, 0, slamParams);
    const hslam_test::SystemRun strict = hslam_test::runSource(dir, 0, strictParams);
    slamAte.push_back(hslam_test::simAte(gt, slam.trajectory));
    strictAte.push_back(hslam_test::simAte(gt, strict.trajectory));
    const vpHSlam::Statistics &s = slam.statistics;
    runsWithLoop += (s.loopsDetected >= 1 && s.loopsCorrected >= 1) ? 1 : 0;
    if (s.loopsCorrected >= 1) { // the stage timings are filled in when a loop went through every stage
      EXPECT_GT(s.loopDetectionMsMean, 0.);
      EXPECT_GT(s.loopVerificationMsMax, 0.);
      EXPECT_GT(s.loopVerificationMsMean, 0.); // a part of detection, spread over every keyframe queried
      EXPECT_LE(s.loopVerificationMsMean, s.loopDetectionMsMean);
      EXPECT_GE(s.loopCorrectionMsMax, s.lastLoopCorrectionMs);
      EXPECT_GT(s.lastLoopCorrectionMs, 0.);
      EXPECT_EQ(s.globalBundleAdjustments, 0u); // off by default (docs/global-map-and-loops.md)
      // No frame far off: the frames before the initialisation, tracked backwards while the camera turned away
      // from the map, stop where the map leaves the view (they went 0.4 m wrong, 40x the run's RMSE, before that
      // check). Relative to the run's RMSE: since the initialisation's check allows for image noise the run
      // starts at frame 8 instead of 324 and includes the room's far side twice, where the worst frames are
      // 2.7-3.8x the RMSE (0.06-0.18 m) without anything being wrong.
      vpHSlamTrajectoryEvaluator evaluator(gt, slam.trajectory, 0.01);
      const vpHSlamTrajectoryEvaluator::AteResult ate = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3);
      EXPECT_LT(ate.error.max, 5. * ate.error.rmse);
    }
    std::cout << "outward loop, budget " << budget << ": slam tracked " << s.trackedFrames << "/" << kFrames
              << ", loops " << s.loopsDetected << " (" << s.loopsCorrected << " corrected, detection "
              << s.loopDetectionMsMean << " ms per keyframe, longest verification " << s.loopVerificationMsMax
              << " ms, longest correction " << s.loopCorrectionMsMax << " ms), ATE " << slamAte.back()
              << " m; vo-strict tracked " << strict.statistics.trackedFrames << ", " << strict.statistics.segments
              << " segment(s), ATE " << strictAte.back() << " m" << std::endl;
  }
  {
    // With loop.globalBundleAdjustment on, the global bundle adjustment follows every correction, in order, and
    // lowers the reprojection error.
    vpHSlamParameters params = fastPreset(vpHSlamParameters::modeSlam);
    params.loop.globalBundleAdjustment = true;
    const hslam_test::SystemRun run = hslam_test::runSource(dir, 0, params);
    const vpHSlam::Statistics &s = run.statistics;
    EXPECT_GE(s.loopsCorrected, 1u);
    EXPECT_EQ(s.globalBundleAdjustments, s.loopsCorrected);
    EXPECT_EQ(s.globalBundleAdjustmentsApplied, s.globalBundleAdjustments);
    EXPECT_LT(s.globalBundleAdjustmentRmsAfterPx, s.globalBundleAdjustmentRmsBeforePx);
    std::cout << "outward loop with the global bundle adjustment: " << s.globalBundleAdjustments << " run, RMS "
              << s.globalBundleAdjustmentRmsBeforePx << " -> " << s.globalBundleAdjustmentRmsAfterPx << " px, ATE "
              << hslam_test::simAte(gt, run.trajectory) << " m" << std::endl;
  }
  std::sort(slamAte.begin(), slamAte.end());
  std::sort(strictAte.begin(), strictAte.end());
  EXPECT_GE(runsWithLoop, 2);
  // Issue 10's bar: slam at least 3x better than vo-strict (medians; 3.5x measured on these five runs: 0.015 /
  // 0.017 / 0.028 / 0.039 / 0.019 m against 0.069 / 0.055 / 0.067 / 0.030 / 0.339 m; 3.4x over the 11 budgets
  // 475..525 of the benchmark in docs/global-map-and-loops.md). Three budgets are too few: 490 / 500 / 510 alone
  // give 2.0x.
  EXPECT_LT(3. * slamAte[2], strictAte[2]);
  EXPECT_LT(slamAte[2], 0.05);
}

TEST(SystemLoop, NoFalseLoopOnSequencesWithoutOne)
{
  int found = 0;
  for (const char *name : {"kitti06_000-050", "tsukuba_cg_000-149", "7scenes_redkitchen_000-299"}) {
    const std::string path = hslam_test::sharedData(name);
    if (path.empty()) {
      std::cout << name << ": not found under " << hslam_test::sharedDataDir() << ", skipped" << std::endl;
      continue;
    }
    ++found;
    const hslam_test::SystemRun run = hslam_test::runSource(path, 0, fastPreset(vpHSlamParameters::modeSlam));
    std::cout << name << ": " << run.statistics.loopsDetected << " loops, " << run.statistics.loopCandidatesVerified
              << " candidates verified" << std::endl;
    EXPECT_EQ(run.statistics.loopsDetected, 0u) << name;
  }
  if (found == 0) {
    GTEST_SKIP() << "no shared sequence found under " << hslam_test::sharedDataDir()
                 << " (set HSLAM_SHARED_DATA_DIR to run this test)";
  }
}

TEST(SystemLoop, RealTimeLoopCorrectionRunsBesideTracking)
{
  // The outward loop fed at the camera's rate in real-time mode: the correction runs in the mapping thread and the
  // global bundle adjustment on a third one while tracking goes on (run under ThreadSanitizer in CI). Whether the
  // loop is found depends on scheduling (mapping skips frames when it falls behind), so only what must always hold
  // is checked: every frame processed, one bundle adjustment per correction, the last one written back by
  // synchronize().
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";
  }
  const std::string dir = outwardLoop();
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  vpHSlamParameters params = fastPreset(vpHSlamParameters::modeSlam);
  params.system.deterministic = false;
  params.loop.globalBundleAdjustment = true; // off by default; on here so its thread runs (and is checked)
  params.features.desiredImmatureDensity = 490;
  vpHSlam slam(*source, params);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  unsigned int fed = 0;
  const auto start = std::chrono::steady_clock::now();
  while (source->acquire(I, frame)) {
    std::this_thread::sleep_until(start + std::chrono::duration<double>(fed / 30.));
    slam.track(I, frame.timestamp, frame.exposure);
    ++fed;
  }
  slam.synchronize();
  const vpHSlam::Statistics s = slam.getStatistics();
  std::cout << "real time: tracked " << s.trackedFrames << "/" << fed << ", loops corrected " << s.loopsCorrected
            << ", global bundle adjustments " << s.globalBundleAdjustments << " (" << s.globalBundleAdjustmentsApplied
            << " applied, longest " << s.globalBundleAdjustmentSecondsMax << " s, RMS "
            << s.globalBundleAdjustmentRmsBeforePx << " -> " << s.globalBundleAdjustmentRmsAfterPx
            << " px), frames tracked during a correction " << s.framesDuringLoopCorrection << " (longest "
            << s.trackingMsMaxDuringLoopCorrection << " ms)" << std::endl;
  EXPECT_EQ(s.frames, fed);
  EXPECT_EQ(slam.getTrajectory().size(), s.trackedFrames);
  EXPECT_EQ(s.globalBundleAdjustments, s.loopsCorrected);
  EXPECT_LE(s.globalBundleAdjustmentsApplied, s.globalBundleAdjustments);
  if (s.loopsCorrected >= 1) {
    EXPECT_GE(s.globalBundleAdjustmentsApplied, 1u); // the last one is waited for by synchronize()
    EXPECT_LT(s.globalBundleAdjustmentRmsAfterPx, s.globalBundleAdjustmentRmsBeforePx);
  }
}
