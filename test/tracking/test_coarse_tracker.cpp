// Coarse-to-fine direct alignment on the synthetic scene with exact inverse depths: recovered poses against the
// exact ground truth, brightness changes, bad initial guesses through the motion hypotheses, and failure on an
// unrelated image.
#include "HSlamTestData.h"
#include "TrackingTestUtils.h"

#include <visp3/core/vpMath.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

using namespace hslam;

namespace
{
constexpr unsigned int kWidth = 640;
constexpr unsigned int kHeight = 480;
constexpr unsigned int kFrames = 100;
constexpr int kReferencePoints = 2000;
// Tolerances at these baselines (up to ~10 cm, ~3 degrees): exact depths, noise-free images.
constexpr double kMaxTranslationError = 1e-3; // metres
constexpr double kMaxRotationErrorDeg = 0.05;
// Residual level at convergence and brightness accuracy: at the exact pose the (blurred, see makeFrame) renderings
// still differ by ~ 3 grey levels RMS at the selected edges, and interpolation lowers the contrast of the warped
// image by ~ 2 %, which (a, b) absorb: a ~ -0.02, b ~ +2.3 when nothing changed.
constexpr double kMaxRmse = 4.;
constexpr double kMaxGainBias = 0.03;
constexpr double kMaxOffsetBias = 3.;

#define REQUIRE_TEXTURES()                                                                                             \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";                        \
  }

class CoarseTrackerTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    if (hslam_test::vispImagesDir().empty()) {
      return;
    }
    scene.configure(kWidth, kHeight, kFrames, 30.0, 1);
    hslam_test::makeFrame(scene, 0, params, reference);
    points = hslam_test::selectPoints(scene, 0, reference, kReferencePoints);
  }

  //! First frame whose camera centre is at least \e distance (metres) away from frame 0's.
  unsigned int frameAtDistance(double distance) const
  {
    const vpTranslationVector c0 = scene.getPose(0).getTranslationVector();
    for (unsigned int i = 1; i < kFrames; ++i) {
      if ((scene.getPose(i).getTranslationVector() - c0).frobeniusNorm() >= distance) {
        return i;
      }
    }
    return 0;
  }

  //! The last two frames at \e frame's pose: the constant-velocity prediction is exact.
  CoarseMotionHistory exactHistory(unsigned int frame) const
  {
    CoarseMotionHistory history;
    history.valid = true;
    history.lastMref = history.prelastMref = hslam_test::groundTruthNewMref(scene, 0, frame);
    return history;
  }

  /*!
    Tracks the frame 3 cm from the reference with an exact prediction into \e frame (its RMSE, in \e rmse, is what
    ends the next frame's hypotheses early) and returns it with the frame 5 cm away; {0, 0} when that fails.
  */
  std::pair<unsigned int, unsigned int> trackTheFirstOfTwoFrames(CoarseTracker &tracker, Frame &frame, double &rmse)
  {
    const unsigned int first = frameAtDistance(0.03), second = frameAtDistance(0.05);
    SE3d newMref;
    AffineBrightness affine;
    CoarseTrackingResult result;
    hslam_test::makeFrame(scene, first, params, frame);
    if (first == 0 || second <= first ||
        !tracker.trackWithHypotheses(frame, exactHistory(first), newMref, affine, result)) {
      return {0u, 0u};
    }
    rmse = result.rmse[0];
    return {first, second};
  }

  void expectPose(const SE3d &estimate, unsigned int target, const char *what)
  {
    double dt = 0., dr = 0.;
    hslam_test::poseError(estimate, hslam_test::groundTruthNewMref(scene, 0, target), dt, dr);
    EXPECT_LT(dt, kMaxTranslationError) << what << ", frame " << target;
    EXPECT_LT(dr, kMaxRotationErrorDeg) << what << ", frame " << target;
  }

  vpHSlamParameters::Tracker params;
  vpHSlamSyntheticScene scene;
  Frame reference;
  std::vector<CoarseTrackerPoint> points;
};
} // namespace

TEST_F(CoarseTrackerTest, buildsSparseDepthPerLevel)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  ASSERT_GE(points.size(), 500u);
  tracker.setReference(reference, points);
  ASSERT_EQ(tracker.numLevels(), reference.pyramid.numLevels());
  ASSERT_GE(tracker.numLevels(), 3);
  // Dilation adds pixels around every point at level 0; coarser levels merge 2x2 blocks.
  EXPECT_GT(tracker.numPoints(0), static_cast<int>(points.size()));
  for (int l = 1; l < tracker.numLevels(); ++l) {
    EXPECT_GT(tracker.numPoints(l), 0) << "level " << l;
    EXPECT_LT(tracker.numPoints(l), tracker.numPoints(l - 1) + 1) << "level " << l;
  }
}

TEST_F(CoarseTrackerTest, identityOnTheReferenceItself)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.track(reference, newMref, affine, result)) << coarseTrackingStatusName(result.status);
  EXPECT_LT(newMref.translation().norm(), 1e-5);
  EXPECT_LT(newMref.log().tail<3>().norm(), 1e-6);
  EXPECT_LT(result.rmse[0], 0.05);
  EXPECT_LT(result.flowRT, 1e-6);
  EXPECT_DOUBLE_EQ(result.inlierRatio, 1.);
}

TEST_F(CoarseTrackerTest, tracksFramesAgainstExactGroundTruth)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  SE3d newMref; // start each frame from the previous estimate, as the system's zero-motion hypothesis would
  AffineBrightness affine;
  Frame frame;
  const unsigned int last = frameAtDistance(0.1);
  ASSERT_GT(last, 3u);
  for (unsigned int i = 1; i <= last; ++i) {
    hslam_test::makeFrame(scene, i, params, frame);
    CoarseTrackingResult result;
    ASSERT_TRUE(tracker.track(frame, newMref, affine, result))
        << "frame " << i << ": " << coarseTrackingStatusName(result.status);
    expectPose(newMref, i, "plain");
    EXPECT_GT(result.inlierRatio, 0.9) << "frame " << i;
    EXPECT_LT(result.rmse[0], kMaxRmse) << "frame " << i;
    EXPECT_LT(std::fabs(affine.a), kMaxGainBias) << "frame " << i;
    EXPECT_LT(std::fabs(affine.b), kMaxOffsetBias) << "frame " << i;
    EXPECT_GT(result.flowT, 0.) << "frame " << i;
    EXPECT_GT(result.flowRT, 0.) << "frame " << i;
  }
}

TEST_F(CoarseTrackerTest, recoversGlobalBrightnessChange)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  const double gain = 1.2, offset = 10.;
  const unsigned int target = frameAtDistance(0.03);
  Frame frame;
  hslam_test::makeFrame(scene, target, params, frame, gain, offset);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.track(frame, newMref, affine, result)) << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "I*1.2+10");
  EXPECT_NEAR(affine.a, std::log(gain), kMaxGainBias);
  EXPECT_NEAR(affine.b, offset, kMaxOffsetBias);
  EXPECT_GT(result.inlierRatio, 0.9);
}

TEST_F(CoarseTrackerTest, calibratedPriorKeepsGainFixed)
{
  REQUIRE_TEXTURES();
  // With photometric calibration the (default) prior 1e12 fixes a: a pure offset change is absorbed by b.
  CoarseTracker tracker(params, true);
  tracker.setReference(reference, points);
  const unsigned int target = frameAtDistance(0.03);
  Frame frame;
  hslam_test::makeFrame(scene, target, params, frame, 1., 5.);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.track(frame, newMref, affine, result)) << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "offset 5, calibrated");
  EXPECT_LT(std::fabs(affine.a), 1e-3); // free: ~ -0.02 (see kMaxGainBias)
  EXPECT_NEAR(affine.b, 5., 0.5);
}

TEST_F(CoarseTrackerTest, pointsHostedElsewhereAreProjectedIntoTheReference)
{
  REQUIRE_TEXTURES();
  // Points with exact depth in frame 6 expressed in frame 0 (the reference) give the same accuracy.
  const unsigned int host = 6;
  Frame hostFrame;
  hslam_test::makeFrame(scene, host, params, hostFrame);
  const std::vector<CoarseTrackerPoint> hosted = hslam_test::selectPoints(scene, host, hostFrame, kReferencePoints);
  const SE3d refMhost = hslam_test::groundTruthNewMref(scene, host, 0);
  std::vector<CoarseTrackerPoint> projected;
  int inside = 0;
  for (const CoarseTrackerPoint &p : hosted) {
    CoarseTrackerPoint q;
    if (projectIntoReference(refMhost, hslam_test::sceneIntrinsics(scene), kWidth, kHeight, p.u, p.v, p.idepth, 1.f,
                             q)) {
      ++inside;
      // The projected inverse depth is the reference's own (up to occlusions: compare only visible surfaces).
      const double idepthRef = 1. / scene.depthAt(q.u, q.v, 0);
      if (std::fabs(idepthRef - q.idepth) < 0.01 * idepthRef) {
        projected.push_back(q);
      }
    }
  }
  ASSERT_GT(inside, static_cast<int>(hosted.size()) / 2);
  ASSERT_GT(projected.size(), 0.8 * inside);
  CoarseTracker tracker(params);
  tracker.setReference(reference, projected);
  const unsigned int target = 3;
  Frame frame;
  hslam_test::makeFrame(scene, target, params, frame);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.track(frame, newMref, affine, result)) << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "projected points");
}

TEST_F(CoarseTrackerTest, hypothesesRecoverFromZeroMotionGuess)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  const unsigned int target = frameAtDistance(0.05);
  ASSERT_GT(target, 0u);
  Frame frame;
  hslam_test::makeFrame(scene, target, params, frame);

  CoarseMotionHistory history; // the last frames did not move: every basic hypothesis is the identity
  history.valid = true;
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.trackWithHypotheses(frame, history, newMref, affine, result))
      << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "zero-motion history");
  EXPECT_GE(result.hypothesesTried, 1);
  EXPECT_TRUE(std::isfinite(tracker.firstRmse()));
}

TEST_F(CoarseTrackerTest, hypothesesRecoverFromMisleadingVelocity)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  const unsigned int target = frameAtDistance(0.05);
  Frame frame;
  hslam_test::makeFrame(scene, target, params, frame);
  // The history claims the camera moved 6 cm backwards and rotated 4 degrees between the last two frames.
  CoarseMotionHistory history;
  history.valid = true;
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.0, 0.0, -0.06, 0.0, 0.07, 0.0;
  history.prelastMref = SE3d::exp(-xi);
  history.lastMref = SE3d();
  std::vector<SE3d> hypotheses;
  CoarseTracker::makeMotionHypotheses(history, hypotheses);
  EXPECT_EQ(hypotheses.size(), 5u + 2u * 26u);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.trackWithHypotheses(frame, history, newMref, affine, result))
      << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "misleading history");
}

TEST_F(CoarseTrackerTest, indirectPoseIsTriedAfterTheConstantVelocityPrediction)
{
  // Hybrid tracking hands the pose of its indirect step to trackWithHypotheses(). With a motion history the
  // constant-velocity prediction is tried first and the indirect pose second; without one, the indirect pose first.
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  Frame frame;
  double firstRmse = 0.;
  const unsigned int target = trackTheFirstOfTwoFrames(tracker, frame, firstRmse).second;
  ASSERT_GT(target, 0u);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;

  // An indirect pose 30 cm and 20 degrees away from the truth (wrong matches): the prediction wins at once.
  hslam_test::makeFrame(scene, target, params, frame);
  CoarseMotionHistory history = exactHistory(target);
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.3, 0., 0., 0., vpMath::rad(20.), 0.;
  history.hasIndirectPose = true;
  history.indirectMref = SE3d::exp(xi) * history.lastMref;
  ASSERT_TRUE(tracker.trackWithHypotheses(frame, history, newMref, affine, result))
      << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "exact prediction, wrong indirect pose");
  EXPECT_EQ(result.hypothesesTried, 1);

  // No history: the indirect pose (here the truth) comes before "no motion from the reference".
  CoarseMotionHistory noHistory;
  noHistory.hasIndirectPose = true;
  noHistory.indirectMref = hslam_test::groundTruthNewMref(scene, 0, target);
  ASSERT_TRUE(tracker.trackWithHypotheses(frame, noHistory, newMref, affine, result))
      << coarseTrackingStatusName(result.status);
  expectPose(newMref, target, "no history, exact indirect pose");
  EXPECT_EQ(result.hypothesesTried, 1);
}

TEST_F(CoarseTrackerTest, aRepeatedImageDoesNotMakeTheNextFrameTryEveryHypothesis)
{
  // A camera that delivers an image twice: the repeat, here the reference image itself, aligns with an RMSE near 0.
  // It beats the frame before by far more than the retrack factor, so the next frame is measured against that
  // frame's RMSE, and an exact prediction still ends the hypotheses at once (against the repeat's, all 57 ran).
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  Frame frame;
  double movedRmse = 0.;
  const unsigned int next = trackTheFirstOfTwoFrames(tracker, frame, movedRmse).second;
  ASSERT_GT(next, 0u);
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  ASSERT_TRUE(tracker.trackWithHypotheses(reference, exactHistory(0), newMref, affine, result));
  ASSERT_LT(result.rmse[0], 0.1 * movedRmse) << "the repeated image should align almost exactly";
  hslam_test::makeFrame(scene, next, params, frame);
  ASSERT_TRUE(tracker.trackWithHypotheses(frame, exactHistory(next), newMref, affine, result))
      << coarseTrackingStatusName(result.status);
  expectPose(newMref, next, "frame after a repeated image");
  EXPECT_EQ(result.hypothesesTried, 1);
}

TEST(CoarseTrackerBound, aFailedLevelDoesNotLowerTheHypothesisBound)
{
  // trackWithHypotheses() bounds each hypothesis by the best RMSE per level so far (finest level first).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // An attempt's outcome: its status, the level where it failed (-1: none) and its RMSE at levels 0, 1, 2.
  auto attempt = [nan](CoarseTrackingStatus status, int failedLevel, double r0, double r1, double r2) {
    CoarseTrackingResult a;
    a.success = status == CoarseTrackingStatus::ok;
    a.status = status;
    a.failedLevel = failedLevel;
    a.rmse.fill(nan);
    a.rmse[0] = r0;
    a.rmse[1] = r1;
    a.rmse[2] = r2;
    return a;
  };
  // The first hypothesis succeeded: 6.28 / 4.03 / 6.07 (the hand-held turn's frame 315).
  CoarseRmsePerLevel achieved;
  achieved.fill(nan);
  CoarseTracker::lowerHypothesisBound(achieved, attempt(CoarseTrackingStatus::ok, -1, 6.28, 4.03, 6.07));
  const std::vector<double> first = {6.28, 4.03, 6.07};
  auto expectBound = [&achieved](const std::vector<double> &expected, const char *what) {
    for (size_t l = 0; l < expected.size(); ++l) {
      EXPECT_DOUBLE_EQ(achieved[l], expected[l]) << what << ", level " << l;
    }
    EXPECT_TRUE(std::isnan(achieved[3])) << what;
  };
  expectBound(first, "first success");

  // A hypothesis whose brightness collapsed at the coarsest level: its 1.53 there is no fit and bounds nothing.
  CoarseTracker::lowerHypothesisBound(achieved,
                                      attempt(CoarseTrackingStatus::implausibleBrightness, 2, nan, nan, 1.53));
  expectBound(first, "brightness failure at level 2");

  // One that passed level 2 at 5.5 and failed at level 1: level 2 is lowered, level 1 is not.
  CoarseTracker::lowerHypothesisBound(achieved, attempt(CoarseTrackingStatus::tooManyOutliers, 1, nan, 0.5, 5.5));
  expectBound({6.28, 4.03, 5.5}, "failure at level 1");

  // A success lowers every level it beats, the finest included.
  CoarseTracker::lowerHypothesisBound(achieved, attempt(CoarseTrackingStatus::ok, -1, 3.9, 4.1, 5.0));
  expectBound({3.9, 4.03, 5.0}, "second success");
}

TEST_F(CoarseTrackerTest, unrelatedImagesAreReportedAsFailures)
{
  REQUIRE_TEXTURES();
  CoarseTracker tracker(params);
  tracker.setReference(reference, points);
  const SE3d guess;
  CoarseMotionHistory history;
  history.valid = true;

  // (1) The reference image turned by 180 degrees: same intensity statistics, unrelated content at every pixel.
  // (Frames far along the camera loop are no use here: the tracker follows them, e.g. 21 cm and 3.5 degrees away.)
  const PyramidLevel &L0 = reference.pyramid.level(0);
  vpImage<float> turned(kHeight, kWidth);
  for (unsigned int k = 0; k < turned.getSize(); ++k) {
    turned.bitmap[k] = L0.color[turned.getSize() - 1 - k][0];
  }
  Frame turnedFrame;
  turnedFrame.pyramid.build(turned, hslam_test::sceneIntrinsics(scene), params.maxPyramidLevels,
                            params.minCoarsestPixels);
  SE3d newMref = guess;
  AffineBrightness affine;
  CoarseTrackingResult result;
  EXPECT_FALSE(tracker.trackWithHypotheses(turnedFrame, history, newMref, affine, result));
  EXPECT_FALSE(result.success);
  EXPECT_NE(result.status, CoarseTrackingStatus::ok) << coarseTrackingStatusName(result.status);

  // (2) Uniform noise of the same size: no structure at all.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> grey(0, 255);
  vpImage<float> noise(kHeight, kWidth);
  for (unsigned int k = 0; k < noise.getSize(); ++k) {
    noise.bitmap[k] = static_cast<float>(grey(rng));
  }
  Frame noiseFrame;
  noiseFrame.pyramid.build(noise, hslam_test::sceneIntrinsics(scene), params.maxPyramidLevels,
                           params.minCoarsestPixels);
  newMref = guess;
  EXPECT_FALSE(tracker.track(noiseFrame, newMref, affine, result));
  EXPECT_NE(result.status, CoarseTrackingStatus::ok);
  // On failure track() leaves the pose untouched.
  EXPECT_LT(newMref.translation().norm(), 1e-12);
}

TEST(CoarseTrackerApi, rejectsInvalidSetup)
{
  vpHSlamParameters::Tracker params;
  params.iterationsPerLevel.clear();
  EXPECT_THROW(CoarseTracker tracker(params), vpHSlamException);
  // Tracking before setReference() is a reported failure, not an exception.
  vpHSlamParameters::Tracker good;
  CoarseTracker tracker(good);
  Frame frame;
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  EXPECT_FALSE(tracker.track(frame, newMref, affine, result));
  EXPECT_EQ(result.status, CoarseTrackingStatus::noReference);
}

TEST(CoarseTrackerApi, projectIntoReferenceRoundTrip)
{
  PinholeIntrinsics K;
  K.fx = 250.;
  K.fy = 250.;
  K.cx = 159.5;
  K.cy = 119.5;
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.1, -0.05, 0.2, 0.02, -0.03, 0.01;
  const SE3d refMhost = SE3d::exp(xi);
  const Eigen::Vector3d pHost(0.3, -0.2, 2.5);
  const float u = static_cast<float>(K.fx * pHost[0] / pHost[2] + K.cx);
  const float v = static_cast<float>(K.fy * pHost[1] / pHost[2] + K.cy);
  CoarseTrackerPoint q;
  ASSERT_TRUE(projectIntoReference(refMhost, K, 320, 240, u, v, static_cast<float>(1. / pHost[2]), 2.f, q));
  const Eigen::Vector3d pRef = refMhost * pHost;
  EXPECT_NEAR(q.u, K.fx * pRef[0] / pRef[2] + K.cx, 1e-3);
  EXPECT_NEAR(q.v, K.fy * pRef[1] / pRef[2] + K.cy, 1e-3);
  EXPECT_NEAR(q.idepth, 1. / pRef[2], 1e-6);
  EXPECT_EQ(q.weight, 2.f);
  // Behind the camera.
  EXPECT_FALSE(projectIntoReference(SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0, 0, -5, 0, 0, 0).finished()), K, 320,
                                    240, u, v, static_cast<float>(1. / pHost[2]), 1.f, q));
}
