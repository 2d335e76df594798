/*
 * H-SLAM for ViSP.
 */
/*!
  \file TrackingReference.h
  \brief What the tracker aligns a new frame against: the window's active points expressed in its newest keyframe
  (DSO makeCoarseDepthL0), or the stored points of a loaded map around a located frame (localisation-only).
*/
#ifndef HSLAM_TRACKING_TRACKING_REFERENCE_H
#define HSLAM_TRACKING_TRACKING_REFERENCE_H

#include "features/ImagePyramid.h"
#include "map/AffineBrightness.h"
#include "map/GlobalMap.h"
#include "map/Keyframe.h"
#include "tracking/CoarseTracker.h"

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
/*!
  The tracking reference of the window.

  What it owns: the active points of the window expressed in the newest keyframe (inverse depth and weight), the
  described corners among them (hybrid tracking's indirect step) and the id of the keyframe they are expressed in.

  What it is given: the window after each keyframe's optimisation (build()). What it hands back: a CoarseTracker set
  to that reference (applyTo(), on the mapping side; the tracking thread swaps the tracker in).

  Threading: not thread-safe; the mapper owns it.
*/
class VISP_EXPORT TrackingReference
{
public:
  TrackingReference(const PinholeIntrinsics &K0, int width, int height) : m_K0(K0), m_width(width), m_height(height) {}
  //! Every active point of \e window in its newest keyframe (an empty window: no reference).
  void build(const std::vector<KeyframePtr> &window);
  /*!
    Set \e tracker's reference to the keyframe of the last build() (it must still be in \e window) with its points.
    \return false when there is none.
  */
  bool applyTo(const std::vector<KeyframePtr> &window, CoarseTracker &tracker, int &keyframeId,
               AffineBrightness &affine, double &exposure) const;
  //! Drop the reference (a new segment).
  void clear();

  /*!
    Localisation-only: the stored points of \e keyframeIds (any kind, with or without a descriptor) expressed in a
    camera at \e refMw, as a direct tracking reference (the inverse depths of a located frame from the map).
  */
  static void fromStoredPoints(const GlobalMap &map, const std::vector<int> &keyframeIds, const SE3d &refMw,
                               const PinholeIntrinsics &K0, int width, int height,
                               std::vector<CoarseTrackerPoint> &points);
  /*!
    Localisation-only: the described stored points of \e keyframeIds in world coordinates (ReferenceFeature::Xref is
    the world position): what the indirect step matches a frame against.
  */
  static void storedFeatures(const GlobalMap &map, const std::vector<int> &keyframeIds, const PinholeIntrinsics &K0,
                             std::vector<ReferenceFeature> &features);

private:
  PinholeIntrinsics m_K0;
  int m_width, m_height;
  std::vector<CoarseTrackerPoint> m_points; //!< tracking reference of the newest keyframe
  std::vector<ReferenceFeature> m_features; //!< its points with descriptors (hybrid tracking)
  int m_keyframe = -1;                      //!< the keyframe they are expressed in
};
} // namespace hslam

#endif
