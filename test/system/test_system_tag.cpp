// Metric poses from an AprilTag (vpHSlam::setTag, map/MetricFrame.h) on the synthetic room: the outward-looking
// camera's two laps (640x480, 400 frames a lap) with a 20 cm tag36h11 on the right wall, filmed from about 2 m in
// frames 60-115 of each lap. One system sees the tag on both laps; a second, fed the same first lap, sees the wall
// without it on the second (the tag taken down). Both must end metric and in the tag's frame: the Sim(3) that best
// aligns their trajectory onto the truth must be the identity within 1 % in scale, 1 cm and 0.5 degree.
#include "HSlamTestTags.h"
#include "SystemTestUtils.h"

#include <visp3/core/vpThetaUVector.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

namespace
{
constexpr unsigned int kLaps = 2, kFramesPerLap = 400, kFrames = kLaps * kFramesPerLap + 1;
constexpr int kTagId = 5;
constexpr double kTagSize = 0.2;

struct FrameError {
  double scale, metres, degrees, ateUnaligned;
};

//! How far the output frame is from the tag's: the Sim(3) aligning the estimate onto the truth, at the trajectory.
FrameError frameError(const vpHSlamTrajectory &truth, const vpHSlamTrajectory &estimate)
{
  const vpHSlamTrajectoryEvaluator evaluator(truth, estimate, 0.001);
  const vpHSlamTrajectoryEvaluator::AteResult sim3 = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3);
  // The alignment moves the estimate's centroid c to s R c + t: its distance to c is the frame's offset there.
  vpColVector c(3, 0.);
  for (const auto &m : evaluator.getMatches()) {
    for (unsigned int k = 0; k < 3; ++k) {
      c[k] += estimate.get_wMc(m.first)[k][3] / evaluator.getMatchedCount();
    }
  }
  const vpColVector moved =
      sim3.scale * (vpColVector(sim3.gMe.getRotationMatrix() * c)) + vpColVector(sim3.gMe.getTranslationVector());
  FrameError e;
  e.scale = std::fabs(sim3.scale - 1.);
  e.metres = (moved - c).frobeniusNorm();
  e.degrees = vpMath::deg(vpThetaUVector(sim3.gMe.getRotationMatrix()).getTheta());
  e.ateUnaligned = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignNone).error.rmse;
  return e;
}
} // namespace

TEST(SystemTag, TagMakesTheTrajectoryMetricAndInItsFrame)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";
  }
  HSLAM_REQUIRE_TAG_IMAGES();
  vpHSlamSyntheticScene scene;
  scene.setLaps(kLaps);
  scene.setLookOutward(true);
  scene.configure(640, 480, kFrames, 30., 1);
  vpColVector centre(3);
  centre[0] = 2.5;
  centre[1] = -0.17;
  centre[2] = 0.8;
  const vpHomogeneousMatrix wMt = hslam_test::hangTag36h11(scene, kTagId, centre, kTagSize);

  if (std::getenv("HSLAM_TEST_DEBUG")) {
    vpHSlamLog::setSink(vpHSlamLog::stderrSink());
    vpHSlamLog::setLevel(vpHSlamLog::debug);
  }
  vpHSlamParameters params;
  params.system.deterministic = true;
  vpHSlam both(hslam_test::syntheticCamera(scene), params), firstLapOnly(hslam_test::syntheticCamera(scene), params);
  const vpHSlamTag tag("tag36h11", kTagSize, kTagId);
  both.setTag(tag);
  firstLapOnly.setTag(tag);
  vpHSlamTrajectory truth; // in the tag's frame
  vpImage<unsigned char> I;
  for (unsigned int i = 0; i < kFrames; ++i) {
    const double t = scene.getTimestamp(i);
    truth.add(t, wMt.inverse() * scene.getPose(i));
    scene.render(i, I);
    both.track(I, t);
    if (i >= kFramesPerLap) { // the second lap without the tag for the other system: one more render
      scene.clearWallPictures();
      scene.render(i, I);
      hslam_test::hangTag36h11(scene, kTagId, centre, kTagSize);
    }
    firstLapOnly.track(I, t);
  }
  for (vpHSlam *slam : {&both, &firstLapOnly}) {
    const bool isBoth = slam == &both;
    const vpHSlam::Statistics s = slam->getStatistics();
    const vpHSlam::WorldFrame w = slam->getWorldFrame();
    const vpHSlamTrajectory estimate = slam->getTrajectory();
    ASSERT_TRUE(w.metric) << (isBoth ? "both laps" : "first lap only") << ": " << w.sightings << " sightings, kept "
                          << w.sightingsUsed << ", scale " << w.scale << " +- " << w.scaleUncertainty << ", rms "
                          << w.rmsMetres << " m";
    EXPECT_TRUE(w.tagFrame);
    const FrameError e = frameError(truth, estimate);
    std::cout << (isBoth ? "tag on both laps" : "tag on the first lap only") << ": tracked " << s.trackedFrames << "/"
              << kFrames << ", loops " << s.loopsCorrected << ", sightings " << w.sightings << " (kept "
              << w.sightingsUsed << "), scale error " << 100. * e.scale << " %, frame offset " << 100. * e.metres
              << " cm, " << e.degrees << " deg; ATE without alignment " << e.ateUnaligned << " m; scale +-"
              << 100. * w.scaleUncertainty << " %, detection " << s.tagDetectionMsMean << " ms per keyframe"
              << std::endl;
    EXPECT_GE(s.trackedFrames, kFrames - 20);
    EXPECT_LT(e.scale, 0.01);
    EXPECT_LT(e.metres, 0.01);
    EXPECT_LT(e.degrees, 0.5);
  }
}
