/*
 * H-SLAM for ViSP.
 */
/*!
  \file MotionContinuation.h
  \brief A lost camera that kept moving (a car after a cover): the motion of its last two tracked frames continued
  over the frames lost since, as motion hypotheses for the frame that returns, and the test that an alignment from
  them ended where that motion predicted.

  Relocalisation looks for a lost camera where the map's points say it is (bag-of-words, the window's points) or
  near its last pose. A car keeps driving while its lens is covered: 3-10 black frames on KITTI 06 leave it 3-8 m on,
  where the window's corners match 4-7 ORB inliers, too few to confirm a pose. An alignment started from the
  continued motion that ends within a fraction of one frame's motion of the prediction is taken as the camera's pose
  without ORB confirmation: converging there is the evidence. A hand-held camera does not keep its motion and its
  alignments end far away (measurements at the constants in MotionContinuation.cpp).

  Ownership: pure functions on CoarseMotionHistory values. Threading: none.
*/
#ifndef HSLAM_TRACKING_MOTION_CONTINUATION_H
#define HSLAM_TRACKING_MOTION_CONTINUATION_H

#include "math/SE3.h"
#include "tracking/CoarseTracker.h"

#include <visp3/core/vpConfig.h>

namespace hslam
{
/*!
  \e history (last and previous tracked frames against the reference) with their motion per step continued so that
  its constant-velocity hypothesis (CoarseTracker::predictConstantVelocity) is \e steps steps after the last frame;
  the other hypotheses lie around it. \e steps is the number of frames since the last tracked one divided by the
  frames between the last two. Invalid (valid false) when \e history is, when \e steps is under 2 (no frame lost
  between: the usual hypotheses cover it) or when there is no motion to continue.
*/
VISP_EXPORT CoarseMotionHistory continueMotion(const CoarseMotionHistory &history, double steps);

//! How far an alignment from a continued motion ended from its prediction.
struct ContinuedMotionCheck {
  double stepShare = 0.;   //!< translation off the prediction, as a share of one step's translation
  double rotationDeg = 0.; //!< rotation off the prediction, degrees
  bool kept = false;       //!< within both bounds: the camera kept moving
};

/*!
  Where \e newMref (the alignment's reference-to-frame pose) ended against the prediction of \e continued (made by
  continueMotion()). The bounds are those of MotionContinuation.cpp.
*/
VISP_EXPORT ContinuedMotionCheck checkContinuedMotion(const CoarseMotionHistory &continued, const SE3d &newMref);
} // namespace hslam

#endif
