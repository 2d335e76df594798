/*
 * H-SLAM for ViSP.
 */
/*!
  \file LostFrameRelocalizer.h
  \brief Relocalisation of a lost frame into the current map (paper section 3.2, failure recovery): place
  recognition, the window's triangulated points, the check that an aligned pose holds, and the stored-map fixes that
  may seed an emptied window again.

  relocalize(): bag-of-words candidates of the map, ORB matching and PnP RANSAC (Relocalizer.h); when that fails, the
  window's keyframes with ORB points triangulated between them (WindowRelocalization.h). The pose found is the start
  of the joint alignment against the tracking reference (FrameTracker), whose result confirmed() then accepts or
  refuses. Each bag-of-words result is kept as the last stored-map fix; two consecutive fixes that agree may seed an
  emptied window (TrackingStateMachine).

  Owns: the window's described views (WindowRelocalization), the matches of the last relocalisation that found a
  pose (they can confirm the aligned pose), the last stored-map fix.
  Is given: the lost frame, the map through TrackingMap, the HybridTracker (the conductor's; keypoints of the frame),
  the tracking reference's keyframe id and brightness. Hands back: a motion history holding the relocalised pose,
  whether the frame had anything to match, the confirmation of an aligned pose, the stored-map fix.

  Threading: the tracking thread.
*/
#ifndef HSLAM_TRACKING_LOST_FRAME_RELOCALIZER_H
#define HSLAM_TRACKING_LOST_FRAME_RELOCALIZER_H

#include "map/AffineBrightness.h"
#include "map/Frame.h"
#include "math/SE3.h"
#include "tracking/CoarseTracker.h"
#include "tracking/HybridTracker.h"
#include "tracking/Relocalizer.h"
#include "tracking/TrackingMap.h"
#include "tracking/WindowRelocalization.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <vector>

namespace hslam
{
/*!
  Place recognition for the frame \e frameId (described as \e features): the bag-of-words candidates of \e map
  (\e preferred first when it is one), ORB matching and PnP RANSAC with tracking.relocalizationMinInliers; logged at
  debug level. Shared by relocalisation and localisation-only.
*/
VISP_EXPORT RelocalizationResult recognizePlace(int frameId, RelocalizationFrame &features, TrackingMap &map,
                                                const vpHSlamParameters::Tracking &params, const PinholeIntrinsics &K,
                                                int preferred = -1);

class VISP_EXPORT LostFrameRelocalizer
{
public:
  //! A lost frame placed by bag-of-words + PnP in the stored map.
  struct StoredMapFix {
    int frameId = -1; //!< -1: none
    SE3d cMw;
    int keyframeId = -1;             //!< the stored keyframe PnP placed it against
    bool agreesWithPrevious = false; //!< the previous frame had a fix too, and the two agree (compareFixes)
  };

  //! \e hybrid and \e map are not owned and must outlive this object.
  LostFrameRelocalizer(const vpHSlamParameters::Tracking &params, const PinholeIntrinsics &K, HybridTracker &hybrid,
                       TrackingMap &map);

  /*!
    Relocalise the lost \e frame. On success \e history holds the pose (no motion) relative to the tracking reference
    \e referenceKeyframe, with brightness \e lastAffine, for the joint refinement that follows. \e described: the
    frame had features to match (false for a black frame).
  */
  bool relocalize(const FramePtr &frame, int referenceKeyframe, const AffineBrightness &lastAffine,
                  CoarseMotionHistory &history, bool &described);
  /*!
    Whether a lost frame's alignment (\e aligned, pose \e cMwAligned, \e result) holds against the map: enough ORB
    inliers of the indirect step \e indirect, or enough of the relocalisation's own matches within reach (see the
    implementation). \e attempt is appended to the debug message.
  */
  bool confirmed(const Frame &frame, bool aligned, const SE3d &cMwAligned, const CoarseTrackingResult &result,
                 const IndirectStepResult &indirect, const char *attempt) const;

  //! The last lost frame's fix (frameId -1: none).
  const StoredMapFix &storedMapFix() const { return m_storedMapFix; }
  void forgetStoredMapFix() { m_storedMapFix = StoredMapFix(); }
  //! Tracking resumed or the window went: its described keyframes would go stale.
  void forgetWindow() { m_window.clear(); }

private:
  //! Keep \e r as the stored-map fix and say whether it agrees with the previous frame's.
  void recordStoredMapFix(const Frame &frame, const RelocalizationResult &r);
  //! The window's triangulated points as the last resort (see WindowRelocalization.h).
  RelocalizationResult relocalizeInWindow(const Frame &frame);

  vpHSlamParameters::Tracking m_params;
  PinholeIntrinsics m_K;
  HybridTracker &m_hybrid;
  TrackingMap &m_map;
  WindowRelocalization m_window; //!< the window's triangulated ORB points
  //! Matches of the last relocalisation that found a pose (world point, pixel): they can confirm the aligned pose.
  std::vector<ReprojectionObservation> m_evidence;
  StoredMapFix m_storedMapFix;
};
} // namespace hslam

#endif
