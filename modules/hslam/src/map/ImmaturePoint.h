/*
 * H-SLAM for ViSP.
 */
/*!
  \file ImmaturePoint.h
  \brief A candidate point whose inverse depth is still an interval, refined by epipolar tracing in new frames.

  DSO's ImmaturePoint: selected in a new keyframe, traced along the epipolar line in every following frame
  (which shrinks [idepthMin, idepthMax]); activated into a MapPoint when the interval is small and the point fits
  the distance map of the newest keyframe.
*/
#ifndef HSLAM_MAP_IMMATURE_POINT_H
#define HSLAM_MAP_IMMATURE_POINT_H

#include "features/BinaryDescriptor.h"
#include "features/PatchPattern.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace hslam
{
//! Outcome of the last epipolar trace (DSO's ImmaturePointStatus).
enum class TraceStatus : uint8_t {
  uninitialized, //!< never traced
  good,          //!< traced, interval updated
  outOfBounds,   //!< projected out of the image: the point will never be traceable again (dropped)
  skipped,       //!< epipolar segment too short to be informative: interval kept
  badCondition,  //!< epipolar line nearly orthogonal to the gradient: interval kept
  outlier        //!< photometric error too large at the best match
};

struct ImmaturePoint {
  int hostKeyframeId = -1;
  float u = 0.f, v = 0.f; //!< host pixel, level 0
  int selectionLevel = 0; //!< pyramid level at which the selector picked it (0, 1 or 2; DSO "type")
  bool isCorner = false;  //!< FAST corner rather than a gradient pixel (descriptor sharing)
  float idepthMin = 0.f;  //!< lower bound of the inverse-depth interval, 1/m
  float idepthMax = std::numeric_limits<float>::infinity(); //!< upper bound (infinite until first trace)
  float quality = 1e4f;        //!< second-best / best matching error ratio of the last trace (DSO)
  float energyThreshold = 0.f; //!< outlier threshold on the summed pattern error
  TraceStatus lastStatus = TraceStatus::uninitialized;
  std::array<float, kPatternSize> patch{};       //!< host intensities of the pattern
  std::array<float, kPatternSize> patchWeight{}; //!< gradient weights of the pattern pixels
  OrbDescriptor orb;                             //!< ORB descriptor at the host pixel (descriptor sharing)
  float orbAngleDeg = 0.f;                       //!< its orientation, degrees
  bool hasOrb = false;                           //!< false in direct mode or too close to the border
  //! Never activated: traced only for its depth, and kept in the global map when its host leaves the window with
  //! that depth converged (hasConvergedDepth()). The first keyframe's corners (LocalMapper::initialize).
  bool descriptorOnly = false;
};

//! An immature point's depth interval is below this share of its sum (+-10 %): it may stand for a map point.
constexpr float kMaxConvergedRelativeInterval = 0.1f;

//! Whether \e pt's last trace was good, its match unambiguous (quality above \e minQuality) and its interval narrow.
inline bool hasConvergedDepth(const ImmaturePoint &pt, float minQuality)
{
  return pt.lastStatus == TraceStatus::good && pt.quality > minQuality && pt.idepthMin > 0.f &&
         std::isfinite(pt.idepthMax) &&
         pt.idepthMax - pt.idepthMin <= kMaxConvergedRelativeInterval * (pt.idepthMax + pt.idepthMin);
}
} // namespace hslam

#endif
