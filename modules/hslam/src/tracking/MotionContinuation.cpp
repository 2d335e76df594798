/*
 * H-SLAM for ViSP.
 */
#include "tracking/MotionContinuation.h"

#include <visp3/core/vpMath.h>

#include <cmath>

namespace hslam
{
namespace
{
//! The motion is continued over a loss only when at least this many steps are missing since the last tracked frame.
constexpr double kMinSteps = 2.;
/*!
  Bounds of an alignment taken without ORB confirmation: translation off the prediction as a share of one step's,
  rotation in degrees. Measured after covers of 3-10 frames on KITTI 06 (budgets 490 / 510, 13 relocalisations):
  0.013-0.055 of a step and 0.12-1.05 degrees, where the window's corners gave 4-7 ORB inliers (15 needed). A
  hand-held camera does not keep its motion: on Tsukuba after 20 black frames the alignments from it that passed the
  photometric checks ended 0.6-11 steps and 1.2-11 degrees away, one of them at a wrong place (ATE 28 cm if taken).
*/
constexpr double kMaxStepShare = 0.25;
constexpr double kMaxRotationDeg = 2.;
//! Below this norm the last two frames' relative pose is rounding error (the map's scale is about 1): no motion.
constexpr double kNoMotion = 1e-9;
} // namespace

CoarseMotionHistory continueMotion(const CoarseMotionHistory &history, double steps)
{
  CoarseMotionHistory continued;
  if (!history.valid || !(steps >= kMinSteps) || !std::isfinite(steps)) {
    return continued;
  }
  const SE3d::Tangent perStep = (history.lastMref * history.prelastMref.inverse()).log();
  if (!perStep.allFinite() || perStep.norm() < kNoMotion) {
    return continued; // no motion to continue
  }
  // The last frame's pose moved on by steps - 1, the frame before it by steps - 2: constant velocity is steps on.
  continued = history;
  continued.lastMref = SE3d::exp((steps - 1.) * perStep) * history.lastMref;
  continued.prelastMref = SE3d::exp((steps - 2.) * perStep) * history.lastMref;
  return continued;
}

ContinuedMotionCheck checkContinuedMotion(const CoarseMotionHistory &continued, const SE3d &newMref)
{
  ContinuedMotionCheck check;
  if (!continued.valid) {
    return check;
  }
  const SE3d off = newMref * CoarseTracker::predictConstantVelocity(continued).inverse();
  const double stepLength = (continued.lastMref * continued.prelastMref.inverse()).translation().norm();
  check.stepShare = stepLength > 0. ? off.translation().norm() / stepLength : HUGE_VAL;
  check.rotationDeg = vpMath::deg(off.log().tail<3>().norm());
  check.kept = check.stepShare <= kMaxStepShare && check.rotationDeg <= kMaxRotationDeg;
  return check;
}
} // namespace hslam
