// Adaptive tracking (tracking.mode = adaptive): the per-frame decision of AdaptiveTrackingPolicy, the predicted
// motion it is measured by (CoarseTracker::meanShiftPx), and FrameTracker on the synthetic scene: a frame with a
// clear photometric solution keeps the direct pose and describes nothing; a large rotation brings the geometric term.
#include "HSlamTestData.h"
#include "TrackingTestUtils.h"

#include "tracking/AdaptiveTracking.h"
#include "tracking/FrameTracker.h"
#include "tracking/HybridTracker.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

using namespace hslam;

namespace
{
constexpr unsigned int kWidth = 640;
constexpr unsigned int kHeight = 480;
constexpr unsigned int kFrames = 100;

#define REQUIRE_TEXTURES()                                                                                             \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";                        \
  }

//! A rotation of \e degrees about the camera's vertical axis, applied after \e pose (newMref).
SE3d turnedBy(const SE3d &pose, double degrees)
{
  Eigen::Matrix<double, 6, 1> twist = Eigen::Matrix<double, 6, 1>::Zero();
  twist(4) = degrees * M_PI / 180.;
  return SE3d::exp(twist) * pose;
}

class AdaptiveTrackingTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    if (hslam_test::vispImagesDir().empty()) {
      return;
    }
    params.tracking.mode = vpHSlamParameters::trackingAdaptive;
    scene.configure(kWidth, kHeight, kFrames, 30.0, 1);
    hslam_test::makeFrame(scene, 0, params.tracker, reference);
    K = hslam_test::sceneIntrinsics(scene);
    hybrid = std::make_unique<HybridTracker>(params, K, static_cast<int>(kWidth), static_cast<int>(kHeight));
    tracker = std::make_unique<FrameTracker>(params, false, static_cast<int>(kWidth), static_cast<int>(kHeight),
                                             hybrid.get());
    auto prepared = std::make_unique<CoarseTracker>(params.tracker);
    prepared->setReference(reference, hslam_test::selectPoints(scene, 0, reference, 2000));
    prepared->setReferenceFeatures(hslam_test::referenceFeatures(scene, 0, reference));
    tracker->adoptReference(prepared, 0, reference.affine, reference.exposure);
  }

  //! The motion history of a camera that was at \e prelast and then at \e last (reference-to-frame poses).
  static CoarseMotionHistory history(const SE3d &prelast, const SE3d &last)
  {
    CoarseMotionHistory h;
    h.valid = true;
    h.prelastMref = prelast;
    h.lastMref = last;
    return h;
  }

  //! The scene rendered at the camera whose reference-to-camera pose is \e newMref, as a tracking frame.
  FramePtr frameAt(const SE3d &newMref) const
  {
    vpImage<unsigned char> I;
    scene.renderAtPose(toVpHomogeneousMatrix(newMref * toSE3(scene.getPose(0).inverse())).inverse(), I);
    auto frame = std::make_shared<Frame>();
    hslam_test::makeFrameFromImage(I, scene, params.tracker, *frame);
    return frame;
  }

  //! Track \e frame with the motion history \e h; its pose error against \e truth.
  bool track(const FramePtr &frame, const CoarseMotionHistory &h, const SE3d &truth, double &dt, double &dr)
  {
    SE3d newMref;
    AffineBrightness affine;
    CoarseTrackingResult result;
    const bool ok = tracker->estimatePose(frame, h, false, newMref, affine, result);
    hslam_test::poseError(newMref, truth, dt, dr);
    return ok;
  }

  vpHSlamParameters params;
  vpHSlamSyntheticScene scene;
  Frame reference;
  PinholeIntrinsics K;
  std::unique_ptr<HybridTracker> hybrid;
  std::unique_ptr<FrameTracker> tracker;
};
} // namespace

TEST(AdaptiveTrackingPolicy, largePredictedMotionBringsTheGeometricTerm)
{
  vpHSlamParameters::Tracking p;
  p.adaptiveMotionPx = 20.;
  const AdaptiveTrackingPolicy policy(p, 640);
  EXPECT_DOUBLE_EQ(policy.motionThresholdPx(), 20.);
  EXPECT_EQ(policy.beforeDirect(true, 5.), GeometricReason::none);
  EXPECT_EQ(policy.beforeDirect(true, 20.), GeometricReason::none);
  EXPECT_EQ(policy.beforeDirect(true, 20.5), GeometricReason::largeMotion);
  // Without a motion history or a measurable shift there is no prediction to doubt.
  EXPECT_EQ(policy.beforeDirect(false, 100.), GeometricReason::none);
  EXPECT_EQ(policy.beforeDirect(true, std::numeric_limits<double>::quiet_NaN()), GeometricReason::none);
  // The threshold is given at 640 px and follows the image width (the same share of the image).
  const AdaptiveTrackingPolicy small(p, 320);
  EXPECT_DOUBLE_EQ(small.motionThresholdPx(), 10.);
  EXPECT_EQ(small.beforeDirect(true, 15.), GeometricReason::largeMotion);
}

TEST(AdaptiveTrackingPolicy, doubtfulDirectOutcomeBringsTheGeometricTerm)
{
  vpHSlamParameters::Tracking p;
  p.adaptiveMotionPx = 20.;
  const AdaptiveTrackingPolicy policy(p, 640);
  CoarseTrackingResult result;
  result.hypothesesTried = 1;
  EXPECT_EQ(policy.afterDirect(true, result, 3.), GeometricReason::none);
  EXPECT_EQ(policy.afterDirect(true, result, std::numeric_limits<double>::quiet_NaN()), GeometricReason::none);
  // The motion found is larger than the threshold although none was predicted (a turn that starts suddenly).
  EXPECT_EQ(policy.afterDirect(true, result, 25.), GeometricReason::largeMotion);
  result.hypothesesTried = 3; // the constant-velocity prediction was not good enough
  EXPECT_EQ(policy.afterDirect(true, result, 3.), GeometricReason::predictionRefused);
  EXPECT_EQ(policy.afterDirect(false, result, 3.), GeometricReason::directFailed);
  EXPECT_STREQ(geometricReasonName(GeometricReason::none), "direct");
  EXPECT_STREQ(geometricReasonName(GeometricReason::largeMotion), "large motion");
}

TEST_F(AdaptiveTrackingTest, predictedShiftMeasuresTheMotionInPixels)
{
  REQUIRE_TEXTURES();
  CoarseTracker coarse(params.tracker);
  EXPECT_TRUE(std::isnan(coarse.meanShiftPx(SE3d(), SE3d()))); // no reference yet
  coarse.setReference(reference, hslam_test::selectPoints(scene, 0, reference, 2000));
  EXPECT_DOUBLE_EQ(coarse.meanShiftPx(SE3d(), SE3d()), 0.);
  // A pure rotation of 2 degrees moves every point by about f tan(2 degrees), more towards the image's sides.
  const double shift = coarse.meanShiftPx(SE3d(), turnedBy(SE3d(), 2.));
  const double centre = K.fx * std::tan(2. * M_PI / 180.);
  EXPECT_GT(shift, centre);
  EXPECT_LT(shift, 1.3 * centre);
}

TEST_F(AdaptiveTrackingTest, clearPhotometricSolutionStaysDirect)
{
  REQUIRE_TEXTURES();
  // Frames 1 and 2 known, frame 3 predicted by constant velocity: ordinary hand-held motion.
  auto frame = std::make_shared<Frame>();
  hslam_test::makeFrame(scene, 3, params.tracker, *frame);
  const CoarseMotionHistory h =
      history(hslam_test::groundTruthNewMref(scene, 0, 1), hslam_test::groundTruthNewMref(scene, 0, 2));
  double dt = 0., dr = 0.;
  ASSERT_TRUE(track(frame, h, hslam_test::groundTruthNewMref(scene, 0, 3), dt, dr));
  EXPECT_EQ(tracker->lastReason(), GeometricReason::none);
  EXPECT_TRUE(hybrid->keypoints().empty()) << "a direct frame describes no keypoint";
  EXPECT_TRUE(tracker->takeHybridSteps().empty());
  EXPECT_LT(dt, 2e-3);
  EXPECT_LT(dr, 0.05);
}

TEST_F(AdaptiveTrackingTest, largeRotationBringsTheGeometricTerm)
{
  REQUIRE_TEXTURES();
  // The camera turns 6 degrees a frame about its vertical axis (a fast pan): after frame 2 it is at 6 degrees,
  // the new frame at 12. The predicted motion moves the points by about 55 px: the geometric term is used at once.
  const SE3d at2 = hslam_test::groundTruthNewMref(scene, 0, 2);
  const SE3d last = turnedBy(at2, 6.), truth = turnedBy(at2, 12.);
  const FramePtr frame = frameAt(truth);
  double dt = 0., dr = 0.;
  ASSERT_TRUE(track(frame, history(at2, last), truth, dt, dr));
  EXPECT_EQ(tracker->lastReason(), GeometricReason::largeMotion);
  EXPECT_FALSE(hybrid->keypoints().empty());
  const std::vector<FrameTracker::HybridStep> steps = tracker->takeHybridSteps();
  ASSERT_EQ(steps.size(), 1u);
  EXPECT_GT(steps[0].inliers, 50);
  EXPECT_LT(dt, 5e-3);
  EXPECT_LT(dr, 0.1);
}

TEST_F(AdaptiveTrackingTest, unpredictedTurnIsCheckedWithTheGeometricTerm)
{
  REQUIRE_TEXTURES();
  // Smooth motion predicted, but the camera turned 5 degrees more: the direct alignment has to leave its prediction
  // (or fails), and the frame is tracked again with the geometric term.
  const SE3d at1 = hslam_test::groundTruthNewMref(scene, 0, 1), at2 = hslam_test::groundTruthNewMref(scene, 0, 2);
  const SE3d truth = turnedBy(hslam_test::groundTruthNewMref(scene, 0, 3), 5.);
  const FramePtr frame = frameAt(truth);
  double dt = 0., dr = 0.;
  ASSERT_TRUE(track(frame, history(at1, at2), truth, dt, dr));
  EXPECT_TRUE(tracker->lastReason() == GeometricReason::predictionRefused ||
              tracker->lastReason() == GeometricReason::directFailed)
      << geometricReasonName(tracker->lastReason());
  EXPECT_EQ(tracker->takeHybridSteps().size(), 1u);
  EXPECT_LT(dt, 5e-3);
  EXPECT_LT(dr, 0.1);
}
