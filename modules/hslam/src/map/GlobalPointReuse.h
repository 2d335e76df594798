/*
 * H-SLAM for ViSP.
 */
/*!
  \file GlobalPointReuse.h
  \brief Finding the global points a keyframe sees again (H-SLAM paper sec. 3.3, early adoption and late fusion).

  What it is for: vo-reuse and slam modes. selectReuseKeyframes() picks the stored keyframes worth searching for
  a keyframe of the window: those co-visible with the window (the graph) and those whose points project into the
  keyframe's image (a revisited place the graph does not link yet), most overlapping first. matchGlobalPoints()
  projects their stored corners into the keyframe and matches them by ORB to the keyframe's corners (OrbMatcher:
  radius, Hamming threshold, ratio, rotation consistency), and gives each match the global point's inverse depth
  and variance carried into the keyframe (first-order propagation of the variance).

  Threading: pure functions of their arguments.
*/
#ifndef HSLAM_MAP_GLOBAL_POINT_REUSE_H
#define HSLAM_MAP_GLOBAL_POINT_REUSE_H

#include "features/ImagePyramid.h"
#include "features/OrbMatcher.h"
#include "map/GlobalMap.h"

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
//! The keyframe global points are matched into.
struct ReuseTarget {
  SE3d cMw;
  PinholeIntrinsics K;
  int width = 0, height = 0;
  int segment = 0;
  bool cornersOnly = true;              //!< search only global points that were FAST corners (else every described one)
  std::vector<FrameKeypoint> keypoints; //!< its points with descriptors (host pixels)
};

//! A global point matched to a keypoint of the target.
struct ReuseMatch {
  int keyframeId = -1;   //!< stored keyframe hosting the global point
  size_t pointIndex = 0; //!< its index there
  int keypoint = -1;     //!< index in ReuseTarget::keypoints
  double idepth = 0.;    //!< the global point's inverse depth in the target camera
  double idepthVar = 0.; //!< its variance in the target camera
  int distance = 0;      //!< Hamming distance
};

/*!
  Stored keyframes of \e segment to search for \e target: co-visible with one of \e windowIds, or with at least
  minProjected of their sampled stored corners projecting into the target image in front of it; at most
  \e maxKeyframes, most projected points first.
*/
VISP_EXPORT std::vector<int> selectReuseKeyframes(const GlobalMap &map, const std::vector<int> &windowIds,
                                                  const ReuseTarget &target, int maxKeyframes);

//! Stored corners of \e keyframes matched into \e target (each global point and each keypoint at most once).
VISP_EXPORT std::vector<ReuseMatch> matchGlobalPoints(const GlobalMap &map, const std::vector<int> &keyframes,
                                                      const ReuseTarget &target, const OrbMatcherOptions &options);

/*!
  Inverse depth of a point (host pixel (u, v), inverse depth \e idepth, variance \e var in the host camera) in
  another camera, targetMhost, with its first-order variance. Returns false when the point is not in front of the
  target camera.
*/
VISP_EXPORT bool transferIdepth(const SE3d &targetMhost, const PinholeIntrinsics &K, double u, double v, double idepth,
                                double var, double &targetU, double &targetV, double &targetIdepth, double &targetVar);

//! Inverse-variance fusion of two estimates of one quantity (LSD-SLAM eq. 13): returns the mean, sets \e var.
VISP_EXPORT double fuseInverseVariance(double a, double varA, double b, double varB, double &var);
} // namespace hslam

#endif
