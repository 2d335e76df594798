/*
 * H-SLAM for ViSP.
 */
/*!
  \file TrackingStateMachine.h
  \brief The tracking state of an initialised camera, frame by frame: tracking, lost, relocalising, continued motion,
  new segment (paper section 3.2 with ORB-SLAM2's relocalisation and DSO's failure handling).

  Each frame is aligned to the reference (FrameTracker). A failed alignment keeps the predicted pose (DSO); more than
  system.maxTrackingFailures in a row and the camera is lost: with a relocalisation index the map stays and lost frames
  try relocalisation into it (LostFrameRelocalizer) until one is confirmed or tracking.relocalizationTimeout passes,
  otherwise the conductor ends the segment and a new one is initialised. A relocalisation found where the camera's
  motion continued (a car after a cover, MotionContinuation.h) hands that motion to the next frame and forces
  keyframes.

  | phase           | event                         | next phase      | what happens |
  |-----------------|-------------------------------|-----------------|-------------------------------------------------|
  | newSegment      | initialized                   | tracking        | conductor: two-view map made, first reference |
  | tracking        | aligned                       | tracking        | failures = 0, keyframe decision, frame mapped |
  | tracking        | failed (<= max in a row)      | tracking        | predicted pose kept, not mapped | | tracking |
  failedTooOften, map indexed   | relocalizing    | frame reported lost, lost since its timestamp   | | tracking |
  failedForGood (no index, NaN) | lost            | conductor ends the segment                      | | any initialised
  | noReference                   | lost            | the window is empty                             | | relocalizing
  | refused (pose not confirmed)  | relocalizing    | frame reported lost, the next one tries         | | relocalizing
  | timedOut                      | lost            | conductor ends the segment                      | | relocalizing
  | relocalized                   | tracking        | window relocalisation forgotten                 | | relocalizing
  | relocalizedMoving             | continuedMotion | motion kept (+ forced keyframes, see the .cpp)  | |
  continuedMotion | aligned                       | continuedMotion | (the relocalised frame itself)                  |
  | continuedMotion | failedForGood (NaN)           | lost            | conductor ends the segment | | continuedMotion |
  motionUsed                    | tracking        | next frame: history from the continued motion   | | any |
  segmentEnded                  | newSegment      | conductor dropped the window (or reset)         | Any other pair
  leaves the phase as it is.

  Owns: the phase, the failures in a row, when the camera was lost, the continued motion, the keyframes still forced,
  the last two frames with a pose in the segment.
  Is given: each frame (preprocessed), the FrameTracker (pose against the reference, keyframe rule), the
  LostFrameRelocalizer (null without relocalisation), the recorded poses through TrackingMap.
  Hands back: per frame an Outcome (tracked with a pose relative to the reference, lost, or end of the segment), the
  frame's cMw and affine set when tracked.

  Threading: the tracking thread.
*/
#ifndef HSLAM_TRACKING_TRACKING_STATE_MACHINE_H
#define HSLAM_TRACKING_TRACKING_STATE_MACHINE_H

#include "map/Frame.h"
#include "math/SE3.h"
#include "tracking/CoarseTracker.h"
#include "tracking/FrameTracker.h"
#include "tracking/LostFrameRelocalizer.h"
#include "tracking/TrackingMap.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <optional>

namespace hslam
{
class VISP_EXPORT TrackingStateMachine
{
public:
  enum class Phase { newSegment, tracking, relocalizing, continuedMotion, lost };
  enum class Event {
    initialized,
    aligned,
    failed,
    failedTooOften,
    failedForGood,
    noReference,
    refused,
    timedOut,
    relocalized,
    relocalizedMoving,
    motionUsed,
    segmentEnded
  };
  //! The transition table of the file comment.
  static Phase next(Phase from, Event event);

  //! What a frame came to.
  struct Outcome {
    enum Report {
      tracked,   //!< the frame has a pose (cMw, affine set); mapped when aligned
      lost,      //!< no pose; the map stays (relocalising)
      endSegment //!< no pose; the conductor ends the segment (Phase::lost)
    };
    Report report = lost;
    bool aligned = false;                 //!< tracked: the alignment succeeded (else the predicted pose)
    SE3d refMc;                           //!< tracked: pose relative to the reference keyframe
    bool needKeyframe = false;            //!< tracked and aligned: the frame becomes a keyframe
    int seedKeyframe = -1;                //!< the frame seeds an emptied window from this stored keyframe
    bool relocalizationAttempted = false; //!< relocalisation ran for the frame
    bool relocalized = false;             //!< the frame was relocalised into the map
  };

  /*!
    \param seedFromStoredMap : the mode keeps and re-uses stored points and tracking.seedFromStoredMap.
    \param relocalization : a vocabulary is loaded, there are keypoints and tracking.relocalize.
    \e frames, \e relocalizer (may be null) and \e map are not owned and must outlive this object.
  */
  TrackingStateMachine(const vpHSlamParameters &params, FrameTracker &frames, LostFrameRelocalizer *relocalizer,
                       TrackingMap &map, bool seedFromStoredMap, bool relocalization);

  Phase phase() const { return m_phase; }
  //! Track \e frame (the reference adopted by the conductor beforehand).
  Outcome track(const FramePtr &frame);
  //! A segment's map exists (initialised): the last two frames with a pose (-1: none).
  void startSegment(int lastFrameId, int prelastFrameId);
  //! The conductor ended the segment (or reset): a new one will be initialised.
  void endSegment();

private:
  //! The motion history a frame starts from, and the ones relocalisation adds.
  struct Start {
    CoarseMotionHistory history, continued, beforeLoss;
  };
  //! An alignment of the frame to the reference.
  struct Alignment {
    bool success = false;
    SE3d newMref;
    AffineBrightness affine;
    CoarseTrackingResult result;
  };

  void transition(Event event) { m_phase = next(m_phase, event); }
  //! The motion of the last two tracked frames relative to the reference at \e wMref (uses the continued motion).
  CoarseMotionHistory motionHistory(const SE3d &wMref);
  //! Relocalisation of a lost frame: the pose it gives, or else the motion continued from before the loss.
  void relocalize(const FramePtr &frame, Start &start);
  //! The window has no point left, and two consecutive stored-map fixes agree: the frame is placed by them.
  bool seedsFromStoredMap(const Frame &frame, const Alignment &a) const;
  //! Whether the relocalised pose holds against the map (else the continued motion is tried).
  bool relocalizationConfirmed(const FramePtr &frame, const SE3d &wMref, const Start &start, Alignment &a);
  void finishRelocalization(const Frame &frame, const Start &start, const Alignment &a, bool seeded);
  //! The failure count, the loss decision, then the pose and keyframe decision of a tracked frame.
  Outcome conclude(const FramePtr &frame, const SE3d &wMref, const Alignment &a, bool relocalizedNow, bool seeded);
  /*!
    Steps of the last two tracked frames' motion from the last one to frame \e frameId (frame ids count the frames
    given, black ones included), for continueMotion(); 0 without two tracked frames.
  */
  double lostSteps(int frameId) const;

  vpHSlamParameters m_params;
  FrameTracker &m_frames;
  LostFrameRelocalizer *m_relocalizer;
  TrackingMap &m_map;
  bool m_seedFromStoredMap;
  bool m_relocalization;
  Phase m_phase = Phase::newSegment;
  int m_consecutiveFailures = 0;
  double m_lostSince = 0.; //!< timestamp of the first frame of the current relocalisation attempt, seconds
  //! Relocalised where the camera's motion continued: that motion per frame (last_M_prelast), the velocity of the
  //! frame after it. Empty otherwise.
  std::optional<SE3d> m_continuedMotion;
  int m_forcedKeyframes = 0; //!< frames still made keyframes whatever their flow (after a continued motion)
  int m_lastFrameId = -1, m_prelastFrameId = -1; //!< last two frames with a pose in this segment
};
} // namespace hslam

#endif
