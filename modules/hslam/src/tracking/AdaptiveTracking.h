/*
 * H-SLAM for ViSP.
 */
/*!
  \file AdaptiveTracking.h
  \brief Adaptive tracking (tracking.mode = adaptive): per frame, whether the pose comes from the direct alignment
  alone or from the paper's joint optimisation (eq. 1-4) with the geometric term of the frame's ORB matches.

  Why: each mode wins somewhere, and by a lot (docs/hybrid-tracking.md, "Adaptive tracking"). Under ordinary motion
  the direct alignment is as accurate as the joint one at a third of the cost; under large motion (skipped frames, a
  fast pan, a hand-held turn about a pivot close behind the camera) the photometric cost has minima the coarse-to-fine
  pyramid cannot tell from the right one, and the ORB matches, which do not need a close start, pin the pose.

  The decision, in two places of the frame:
  - before the direct alignment: the predicted motion, measured as the mean pixel distance between where the
    reference's points land at the last frame's pose and at the constant-velocity prediction (CoarseTracker::
    meanShiftPx), above Tracking::adaptiveMotionPx (pixels at 640 px width): the joint step runs at once
    (GeometricReason::largeMotion), and the direct alignment does not run;
  - after it: the alignment failed (GeometricReason::directFailed), or the constant-velocity prediction did not reach
    DSO's "good enough" residual and other motion hypotheses were tried (GeometricReason::predictionRefused: the
    motion changed, the photometric solution is doubtful), or the pose it found moved the points by more than the
    threshold from the last frame's (GeometricReason::largeMotion: a motion that starts suddenly, such as the first
    frame of a fast turn, which the prediction did not see coming). The joint step then runs from the same start, and
    its pose is kept when it succeeds; otherwise the direct one (when it succeeded) stands.
  A frame given neither reason keeps the direct pose, exactly DSO's, and describes no keypoint.

  Owns: nothing but the threshold. FrameTracker applies the decision and keeps each frame's reason (lastReason()),
  which SlamSystem counts in the run statistics for every posed frame.
  Threading: stateless after construction; the tracking thread.
*/
#ifndef HSLAM_TRACKING_ADAPTIVE_TRACKING_H
#define HSLAM_TRACKING_ADAPTIVE_TRACKING_H

#include "tracking/CoarseTracker.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

namespace hslam
{
//! Why a frame's pose used the geometric term.
enum class GeometricReason {
  none,              //!< direct alignment only
  always,            //!< hybrid or indirect tracking: every frame
  lost,              //!< the camera is being relocalised (the ORB inliers confirm the pose)
  largeMotion,       //!< adaptive: the predicted motion is above Tracking::adaptiveMotionPx
  predictionRefused, //!< adaptive: the direct alignment had to try motions other than the constant-velocity one
  directFailed       //!< adaptive: the direct alignment failed
};

//! Short English name of a reason, for logs.
VISP_EXPORT const char *geometricReasonName(GeometricReason reason);

class VISP_EXPORT AdaptiveTrackingPolicy
{
public:
  /*!
    \param width : rectified image width, pixels (the motion threshold is given at 640 px and scaled with it).
  */
  AdaptiveTrackingPolicy(const vpHSlamParameters::Tracking &params, int width);

  /*!
    Before the direct alignment: GeometricReason::largeMotion when \e predictedShiftPx (CoarseTracker::meanShiftPx
    of the last pose and the prediction, level-0 pixels; NaN when unknown) is above the threshold, none otherwise
    (also without a motion history: \e historyValid false).
  */
  GeometricReason beforeDirect(bool historyValid, double predictedShiftPx) const;
  /*!
    After it: GeometricReason::directFailed when \e success is false, predictionRefused when \e result tried more
    than one hypothesis, largeMotion when \e measuredShiftPx (CoarseTracker::meanShiftPx of the last pose and the
    direct one; NaN when unknown) is above the threshold, none otherwise.
  */
  GeometricReason afterDirect(bool success, const CoarseTrackingResult &result, double measuredShiftPx) const;
  //! The motion threshold at this image width, pixels.
  double motionThresholdPx() const { return m_motionThresholdPx; }

private:
  double m_motionThresholdPx;
};
} // namespace hslam

#endif
