/*
 * H-SLAM for ViSP.
 */
/*!
  \file MapPoint.h
  \brief A map point in inverse-depth form: host keyframe, host pixel, inverse depth, its variance, patch, ORB.

  One representation for the local and the global map (H-SLAM paper, sec. 3.3): while the point is ACTIVE it
  keeps its 8-pixel patch and is optimised in the window; once MARGINALISED its patch is dropped but host,
  pixel, inverse depth, variance and descriptor stay (map/GlobalMap.h), so it can be re-activated later (early
  adoption / late fusion, map/GlobalPointReuse.h).

  Ownership: the mapper owns points (std::unique_ptr in the keyframe that hosts them); tracking reads copies of
  what it needs (host pixel, inverse depth, patch) through the system's snapshot of the window.
*/
#ifndef HSLAM_MAP_MAP_POINT_H
#define HSLAM_MAP_MAP_POINT_H

#include "features/BinaryDescriptor.h"
#include "features/PatchPattern.h"
#include "math/SE3.h"

#include <array>
#include <cstdint>
#include <vector>

namespace hslam
{
//! Where a point was seen in a keyframe other than its host (a measurement for the global bundle adjustment).
struct PixelObservation {
  int keyframeId = -1;
  float u = 0.f, v = 0.f; //!< level-0 pixel
};

//! Life cycle of a point.
enum class PointStatus : uint8_t {
  active,       //!< in the window, optimised by the photometric BA
  marginalized, //!< left the window with its host; kept in the global map (no patch)
  outlier       //!< removed (too many outlier residuals); kept only until memory is reclaimed
};

struct MapPoint {
  int hostKeyframeId = -1; //!< keyframe whose image defines the pixel and the patch
  float u = 0.f;           //!< host pixel, level 0, pixels
  float v = 0.f;           //!< host pixel, level 0, pixels
  double idepth = 0.;      //!< inverse depth in the host camera, 1/metres (up to the monocular scale)
  double idepthVar = 0.;   //!< variance of idepth, from the window Hessian
  PointStatus status = PointStatus::active;
  bool isCorner = false; //!< selected as a FAST corner (descriptor is reliable) rather than a gradient pixel
  std::array<float, kPatternSize> patch{};       //!< host intensities of the pattern pixels (active only)
  std::array<float, kPatternSize> patchWeight{}; //!< gradient-dependent weights c^2/(c^2+|g|^2) per pixel (DSO)
  OrbDescriptor orb;                             //!< 256-bit ORB descriptor at the host pixel (descriptor sharing)
  float orbAngleDeg = 0.f;                       //!< orientation the descriptor was computed at, degrees
  bool hasOrb = false;                           //!< false in direct mode or too close to the border
  //! Other keyframes in which the point had an inlier photometric residual (ids, sorted, unique): co-visibility.
  std::vector<int> observers;
  //! Inverse-depth prior (re-used global point: its old estimate); weight 1 / variance, 0 = no prior.
  double idepthPrior = 0.;
  double idepthPriorWeight = 0.;
  bool fromGlobalMap = false; //!< re-activated or fused from a global point (vo-reuse)
  //! Kept on a depth prior while the camera turned in place (mapper.rotationFlowPx); cleared once the window
  //! measures its depth. Such a point leaving the window unmeasured is dropped, not stored: a guess is no landmark.
  bool depthFromPrior = false;
  //! Measurements a re-used point brings from the global map (its old host pixel and old observers' pixels): the
  //! window only measures it in its own keyframes; the others are kept as they were measured.
  std::vector<PixelObservation> carried;
  //! Anchor of a re-used point (mapping/AnchorResidual.h): the stored keyframe it came from (-1: none), refreshed
  //! from the global map before each window optimisation, and the pixel and inverse depth it had there.
  int anchorKeyframeId = -1;
  SE3d anchorCMw;
  float anchorU = 0.f, anchorV = 0.f;
  double anchorIdepth = 0.;
  double anchorIdepthWeight = 0.; //!< 1 / (stored variance x globalMap.priorVarianceScale)
};

//! Status of a point leaving the window: marginalised (kept in the global map) unless its depth was never measured.
inline PointStatus leavingStatus(const MapPoint &p)
{
  return p.depthFromPrior ? PointStatus::outlier : PointStatus::marginalized;
}

//! The depth guessed while the camera turned is measured now (by the window or a stored point): the point becomes
//! an ordinary one, without the guess's prior.
inline void forgetDepthGuess(MapPoint &p)
{
  p.depthFromPrior = false;
  p.idepthPrior = 0.;
  p.idepthPriorWeight = 0.;
}

//! Adds \e keyframeId to a sorted list of observer ids (no duplicate).
inline void addObserver(std::vector<int> &observers, int keyframeId)
{
  auto it = observers.begin();
  while (it != observers.end() && *it < keyframeId) {
    ++it;
  }
  if (it == observers.end() || *it != keyframeId) {
    observers.insert(it, keyframeId);
  }
}
} // namespace hslam

#endif
