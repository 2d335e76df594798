/*
 * H-SLAM for ViSP.
 */
/*!
  \file FrameTracker.h
  \brief Pose of a frame against the current tracking reference, and whether it becomes a keyframe (paper section
  3.2; DSO FullSystem::trackNewCoarse and the keyframe rule of addActiveFrame).

  Owns: the active CoarseTracker and what its reference is (keyframe id, brightness and exposure when it was set),
  the indirect step of the current frame, the adaptive-tracking policy and why the last frame used the geometric term
  (lastReason()), the brightness of the last tracked frame, the frames since the last keyframe request, and the
  descriptor-matched pixels of the last frame (display).
  Is given: the frame, its motion history (TrackingStateMachine), and the reference the back end prepared
  (adoptReference(), swapped in by the conductor); the HybridTracker (keypoints, indirect step) is the conductor's,
  shared with relocalisation and localisation, null in direct mode without relocalisation.
  Hands back: the pose relative to the reference (newMref), the brightness (a, b), the tracking result, the keyframe
  decision, and per frame the hybrid step's counts (takeHybridSteps(), for the run statistics).

  Threading: the tracking thread; descriptorMatches() from any thread (its own mutex).
*/
#ifndef HSLAM_TRACKING_FRAME_TRACKER_H
#define HSLAM_TRACKING_FRAME_TRACKER_H

#include "map/AffineBrightness.h"
#include "map/Frame.h"
#include "math/SE3.h"
#include "tracking/AdaptiveTracking.h"
#include "tracking/CoarseTracker.h"
#include "tracking/HybridTracker.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <memory>
#include <mutex>
#include <vector>

namespace hslam
{
class VISP_EXPORT FrameTracker
{
public:
  //! Counts of one frame's successful hybrid step (RunStatistics::addHybridFrame).
  struct HybridStep {
    int matches = 0;
    int inliers = 0;
    double geometricWeight = 0.;
  };

  /*!
    \param width, height : rectified image size, pixels (DSO's flow weights are scaled by it).
    \param hybrid : keypoints and the indirect step (not owned; null in direct mode without relocalisation).
  */
  FrameTracker(const vpHSlamParameters &params, bool photometricCalibration, int width, int height,
               HybridTracker *hybrid);

  //! Make \e prepared (set by the back end to keyframe \e keyframeId) the reference; \e prepared gets the old one.
  void adoptReference(std::unique_ptr<CoarseTracker> &prepared, int keyframeId, const AffineBrightness &affine,
                      double exposure);
  //! Forget the reference (the window was dropped).
  void dropReference() { m_referenceKeyframe = -1; }
  bool hasReference() const { return m_referenceKeyframe >= 0; }
  int referenceKeyframe() const { return m_referenceKeyframe; }

  /*!
    Pose of \e frame against the reference: direct (DSO hypotheses), indirect (ORB matches, pose-only), hybrid
    (indirect step, then the joint optimisation seeded by it) or adaptive (direct, hybrid when AdaptiveTrackingPolicy
    says so), per Tracking::mode. \e lost: the camera is being relocalised (with direct or adaptive tracking the joint
    step then runs too: its ORB inliers confirm a relocalised pose).
  */
  bool estimatePose(const FramePtr &frame, CoarseMotionHistory history, bool lost, SE3d &newMref,
                    AffineBrightness &affine, CoarseTrackingResult &result);
  //! The last frame's indirect step (hybrid / indirect tracking, or a lost camera).
  const IndirectStepResult &indirect() const { return m_indirect; }
  //! Why the last frame's pose used the geometric term (GeometricReason::none: direct alignment only).
  GeometricReason lastReason() const { return m_lastReason; }

  /*!
    DSO's keyframe rule for a tracked \e frame (its affine set): weighted optical flow and brightness change, or the
    residual doubled since the reference's first frame; \e forced: made a keyframe whatever its flow.
  */
  bool keyframeNeeded(const FramePtr &frame, const CoarseTrackingResult &result, bool forced);
  //! A keyframe was asked for another way (a window seeded from the stored map): the frame count starts again.
  void noteKeyframeRequested() { m_framesSinceKeyframeRequest = 0; }

  //! A new segment's map exists: its second keyframe's frame has brightness \e affine.
  void startSegment(const AffineBrightness &affine);
  //! vpHSlam::reset(): no reference, the counters start again.
  void reset();
  const AffineBrightness &lastAffine() const { return m_lastAffine; }
  void setLastAffine(const AffineBrightness &affine) { m_lastAffine = affine; }

  //! The hybrid steps of the frames since the last call, oldest first (then forgotten).
  std::vector<HybridStep> takeHybridSteps();
  //! Descriptor-matched inlier pixels of the last frame (display); any thread.
  std::vector<vpImagePoint> descriptorMatches() const;

private:
  //! Adaptive tracking of a frame that is not lost (see AdaptiveTracking.h).
  bool estimateAdaptive(const FramePtr &frame, const CoarseMotionHistory &history, SE3d &newMref,
                        AffineBrightness &affine, CoarseTrackingResult &result);
  //! The indirect step, then the joint (or, indirect mode, geometric) pose; records the step as \e reason's.
  bool estimateJoint(const FramePtr &frame, CoarseMotionHistory history, GeometricReason reason, SE3d &newMref,
                     AffineBrightness &affine, CoarseTrackingResult &result);
  //! The pixels the display shows as matched (none for a frame tracked directly).
  void publishMatches(bool success);

  vpHSlamParameters m_params;
  int m_width, m_height;
  HybridTracker *m_hybrid;
  AdaptiveTrackingPolicy m_adaptive;
  GeometricReason m_lastReason = GeometricReason::none;
  std::unique_ptr<CoarseTracker> m_tracker;
  int m_referenceKeyframe = -1;       //!< keyframe id of m_tracker's reference
  AffineBrightness m_referenceAffine; //!< brightness of the reference when it was set
  double m_referenceExposure = 1.;
  AffineBrightness m_lastAffine; //!< (a, b) of the last tracked frame
  int m_framesSinceKeyframeRequest = 0;
  IndirectStepResult m_indirect; //!< the current frame's indirect step (its term is used by m_tracker)
  std::vector<HybridStep> m_hybridSteps;
  mutable std::mutex m_matchesMutex;
  std::vector<vpImagePoint> m_lastMatches;
};
} // namespace hslam

#endif
