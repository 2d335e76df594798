/*
 * H-SLAM for ViSP.
 */
/*!
  \file MapLocalizer.h
  \brief Localisation-only (system.localizationOnly): every frame placed in a loaded map, which never changes.

  While the previous frame was placed, the stored points around its keyframe are tracked (constant-velocity
  prediction, guided ORB matching, pose-only refinement: the indirect step of hybrid tracking, the world as
  reference), then refined photometrically against the last located frame, whose inverse depths come from the stored
  points; with too few matches that photometric alignment alone may place the frame. Otherwise place recognition and
  PnP relocalise the frame (a PnP pose on too few inliers is accepted when the points around its keyframe, matched by
  projection from it, confirm it). Nothing is initialised, mapped or stored.

  Owns: the keyframe that placed the last located frame, the stored points gathered around a keyframe (world
  coordinates) and their keyframes, the last two located frames (the last one's image is the photometric reference),
  a CoarseTracker for that refinement.
  Is given: each frame (preprocessed), the loaded map through TrackingMap, the HybridTracker (the conductor's).
  Hands back: whether the frame was located and its pose cMw (world = the loaded map's), and whether place
  recognition was tried and succeeded (the run's relocalisation counters).

  Threading: the tracking thread.
*/
#ifndef HSLAM_TRACKING_MAP_LOCALIZER_H
#define HSLAM_TRACKING_MAP_LOCALIZER_H

#include "map/Frame.h"
#include "math/SE3.h"
#include "tracking/CoarseTracker.h"
#include "tracking/HybridTracker.h"
#include "tracking/Relocalizer.h"
#include "tracking/TrackingMap.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <memory>
#include <vector>

namespace hslam
{
class VISP_EXPORT MapLocalizer
{
public:
  //! Outcome of localize().
  struct Result {
    bool located = false;
    SE3d cMw;                      //!< the frame's pose in the loaded map (when located)
    bool recognitionTried = false; //!< place recognition ran (the previous frame was not located, or tracking failed)
    bool recognized = false;       //!< and placed the frame
  };

  //! \e hybrid and \e map are not owned and must outlive this object.
  MapLocalizer(const vpHSlamParameters &params, const PinholeIntrinsics &K, bool photometricCalibration,
               HybridTracker &hybrid, TrackingMap &map);

  //! Place \e frame in the loaded map (its affine may be refined).
  Result localize(const FramePtr &frame);
  //! A map was loaded, or the system reset: nothing located, nothing gathered.
  void reset();

private:
  //! Track \e frame in the map from the last located frame (pose \e wMlast); true when located.
  bool trackInMap(const FramePtr &frame, const SE3d &wMlast, SE3d &cMw, int &inliers, const char *&how);
  //! Place recognition and PnP; true when located.
  bool placeByRecognition(const FramePtr &frame, Result &out, int &inliers, const char *&how);
  /*!
    Refine \e cMw by the photometric alignment against the last located frame (pose \e wMlast), whose inverse depths
    come from the stored points, jointly with the reprojection error of \e matches (the indirect step's inliers, world
    coordinates; null: photometric only). False (cMw unchanged) without a last located frame or when the alignment
    fails.
  */
  bool refine(const FramePtr &frame, const SE3d &wMlast, const GeometricTerm *matches, SE3d &cMw);
  /*!
    Whether the points around the keyframe of \e r's near miss (a PnP pose on too few inliers), matched by projection
    from that pose, place the frame with twice tracking.relocalizationMinInliers inliers, within a frame's motion of
    that pose and without the search's prediction-free recovery; then \e cMw and \e inliers are theirs. The local map
    gathered for that keyframe replaces the one held.
  */
  bool confirmNearMiss(const RelocalizationResult &r, SE3d &cMw, int &inliers);

  vpHSlamParameters m_params;
  PinholeIntrinsics m_K;
  bool m_photometricCalibration;
  HybridTracker &m_hybrid;
  TrackingMap &m_map;
  int m_localizedKeyframe = -1;                     //!< keyframe that placed the last located frame
  int m_localMapKeyframe = -1;                      //!< keyframe m_localMapFeatures were gathered around
  std::vector<ReferenceFeature> m_localMapFeatures; //!< its stored points and its neighbours', world coordinates
  std::vector<int> m_localMapKeyframes;             //!< the keyframes they come from
  FramePtr m_lastFrame;       //!< the last located frame (its image), null when the last frame was not located
  SE3d m_wMlast, m_wMprelast; //!< poses of the last two located frames
  bool m_hasPrelast = false;  //!< the frame before the last one was located too
  std::unique_ptr<CoarseTracker> m_refinementTracker; //!< joint refinement against m_lastFrame
};
} // namespace hslam

#endif
