/*
 * H-SLAM for ViSP.
 */
/*!
  \file TrackingMap.h
  \brief What the tracking thread's components read of the map and the trajectory: an interface the conductor
  (SlamSystem) implements.

  The back end (the window, the global map, the relocalisation index) lives in another thread behind a mutex, and the
  recorded poses behind the trajectory recorder's. The components of tracking/ (TrackingStateMachine,
  LostFrameRelocalizer, MapLocalizer) see only this interface: each call takes the lock it needs for its own duration,
  so they never hold the back end nor its mutex (basalt style: one seam per concern).

  Threading: called from the tracking thread only; implementations lock what they read.
*/
#ifndef HSLAM_TRACKING_TRACKING_MAP_H
#define HSLAM_TRACKING_TRACKING_MAP_H

#include "math/SE3.h"

#include <vector>

namespace hslam
{
struct CoarseTrackerPoint;
struct ReferenceFeature;
struct RelocalizationFrame;
struct RelocalizationKeyframe;
struct WindowView;

class TrackingMap
{
public:
  virtual ~TrackingMap() = default;

  //! Current world pose (wMc) of a keyframe of this run.
  virtual SE3d keyframePose(int keyframeId) const = 0;
  //! Current world pose (wMc) of a frame given a pose in this run; false when it has none.
  virtual bool framePose(int frameId, SE3d &wMc) const = 0;

  //! Wait for a mapping job still running (nothing is queued while the camera is lost).
  virtual void waitForMapping() = 0;
  //! True when keyframes are indexed for relocalisation (a vocabulary was loaded).
  virtual bool indexesKeyframes() const = 0;
  /*!
    Keyframes most similar to a lost frame (bag of words), best first (\e preferred first when it is one), with their
    points (world) and direct index; the frame's direct index is filled on the way.
  */
  virtual std::vector<RelocalizationKeyframe> relocalizationCandidates(RelocalizationFrame &frame, int maxCandidates,
                                                                       int preferred) = 0;
  //! The window's keyframes (id, pose, frame with its raw image), oldest first.
  virtual std::vector<WindowView> windowViews() = 0;

  // ---- localisation-only in a loaded map
  //! The stored points (world) of keyframe \e id and of its neighbours, with the ids of those keyframes.
  virtual void localMapFeatures(int id, std::vector<ReferenceFeature> &features, std::vector<int> &keyframeIds) = 0;
  //! The stored points of \e keyframeIds expressed in a camera at \e refMw, as a direct tracking reference.
  virtual void localMapReference(const std::vector<int> &keyframeIds, const SE3d &refMw,
                                 std::vector<CoarseTrackerPoint> &points) = 0;
  //! Of \e keyframeIds, the stored keyframe whose camera is closest to \e cMw (-1 when none).
  virtual int closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) = 0;
};
} // namespace hslam

#endif
