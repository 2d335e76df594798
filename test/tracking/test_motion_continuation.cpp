// The motion of the last two tracked frames continued over lost frames (a car after a cover): exact predictions for
// a constant-twist motion, and the bounds that decide whether an alignment ended where it predicted.
#include "tracking/MotionContinuation.h"

#include <visp3/core/vpMath.h>

#include <gtest/gtest.h>

using namespace hslam;

namespace
{
//! A camera driving on a gentle curve: 1 m forward, 1 degree of yaw per frame (SE3 tangent, translation first).
SE3d::Tangent carStep()
{
  SE3d::Tangent xi;
  xi << 0.02, 0., 1.0, 0., vpMath::rad(1.), 0.;
  return xi;
}

//! History whose last frame is \e k steps of \e xi after the reference, the frame before \e k - 1 steps.
CoarseMotionHistory historyAfter(const SE3d::Tangent &xi, int k)
{
  CoarseMotionHistory h;
  h.valid = true;
  h.lastMref = SE3d::exp(static_cast<double>(k) * xi);
  h.prelastMref = SE3d::exp(static_cast<double>(k - 1) * xi);
  return h;
}

double translationError(const SE3d &a, const SE3d &b)
{
  return (a * b.inverse()).translation().norm();
}
} // namespace

TEST(MotionContinuation, ConstantVelocityLandsOnTheFrameStepsAhead)
{
  const SE3d::Tangent xi = carStep();
  const CoarseMotionHistory h = historyAfter(xi, 3);
  for (double steps : {2., 6., 11.}) {
    const CoarseMotionHistory continued = continueMotion(h, steps);
    ASSERT_TRUE(continued.valid) << steps;
    const SE3d expected = SE3d::exp((3. + steps) * xi);
    EXPECT_LT(translationError(CoarseTracker::predictConstantVelocity(continued), expected), 1e-9) << steps;
    // The per-step motion is unchanged: the other hypotheses stay one step around the prediction.
    const SE3d step = continued.lastMref * continued.prelastMref.inverse();
    EXPECT_LT((step.log() - xi).norm(), 1e-9) << steps;
  }
}

TEST(MotionContinuation, NothingToContinueGivesAnInvalidHistory)
{
  const CoarseMotionHistory h = historyAfter(carStep(), 3);
  EXPECT_FALSE(continueMotion(h, 1.).valid) << "no frame lost: the usual hypotheses cover it";
  EXPECT_FALSE(continueMotion(h, 0.).valid);
  EXPECT_FALSE(continueMotion(CoarseMotionHistory(), 5.).valid);
  CoarseMotionHistory still = h;
  still.prelastMref = still.lastMref; // no motion between the last two frames
  EXPECT_FALSE(continueMotion(still, 5.).valid);
}

TEST(MotionContinuation, AnAlignmentNearThePredictionIsKeptAndAFarOneIsNot)
{
  const SE3d::Tangent xi = carStep();
  const CoarseMotionHistory continued = continueMotion(historyAfter(xi, 3), 6.);
  ASSERT_TRUE(continued.valid);
  const SE3d predicted = CoarseTracker::predictConstantVelocity(continued);
  const double stepLength = SE3d::exp(xi).translation().norm();

  const ContinuedMotionCheck exact = checkContinuedMotion(continued, predicted);
  EXPECT_TRUE(exact.kept);
  EXPECT_LT(exact.stepShare, 1e-9);
  EXPECT_LT(exact.rotationDeg, 1e-6);

  // 5 % of a step off and half a degree about the optical axis: as measured on KITTI after covers.
  SE3d::Tangent small;
  small << 0.05 * stepLength, 0., 0., 0., 0., vpMath::rad(0.5);
  const ContinuedMotionCheck near = checkContinuedMotion(continued, SE3d::exp(small) * predicted);
  EXPECT_TRUE(near.kept);
  EXPECT_NEAR(near.stepShare, 0.05, 0.01);
  EXPECT_NEAR(near.rotationDeg, 0.5, 0.01);

  SE3d::Tangent far;
  far << 0., 0., -0.6 * stepLength, 0., 0., 0.; // stopped short: the camera did not keep its motion
  const ContinuedMotionCheck shortOf = checkContinuedMotion(continued, SE3d::exp(far) * predicted);
  EXPECT_FALSE(shortOf.kept);
  EXPECT_NEAR(shortOf.stepShare, 0.6, 0.01);

  SE3d::Tangent turned;
  turned << 0., 0., 0., 0., vpMath::rad(3.), 0.; // the right place, a 3 degree turn off
  EXPECT_FALSE(checkContinuedMotion(continued, SE3d::exp(turned) * predicted).kept);
  EXPECT_FALSE(checkContinuedMotion(CoarseMotionHistory(), predicted).kept);
}
