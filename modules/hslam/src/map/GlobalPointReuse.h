/*
 * H-SLAM for ViSP.
 */
/*!
  \file GlobalPointReuse.h
  \brief Finding the global points a keyframe sees again (H-SLAM paper sec. 3.3, early adoption and late fusion).

  What it is for: vo-reuse and slam modes. ReuseKeyframeSelector picks the stored keyframes worth searching for
  a keyframe of the window: those co-visible with the window (the graph) and those whose points project into the
  keyframe's image (a revisited place the graph does not link yet), most overlapping first. matchGlobalPoints()
  projects their stored corners into the keyframe and matches them by ORB to the keyframe's corners (OrbMatcher:
  radius, Hamming threshold, ratio, rotation consistency), and gives each match the global point's inverse depth
  and variance carried into the keyframe (first-order propagation of the variance).

  Threading: the functions are pure functions of their arguments; the selector belongs to one thread.
*/
#ifndef HSLAM_MAP_GLOBAL_POINT_REUSE_H
#define HSLAM_MAP_GLOBAL_POINT_REUSE_H

#include "features/ImagePyramid.h"
#include "features/OrbMatcher.h"
#include "map/GlobalMap.h"

#include <visp3/core/vpConfig.h>

#include <cstdint>
#include <unordered_map>
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
  Picks the stored keyframes of the target's segment to search for \e target: co-visible with one of the window's
  keyframes and with at least one sampled stored corner (every 4th) projecting into the target image in front of it,
  or with at least 10 of them; at most \e maxKeyframes, most projected samples first.

  Why it keeps state: this runs at every keyframe over every stored keyframe, and reading each stored keyframe's
  points again was 20 % of the mapping thread at 5,700 stored keyframes (hslam_many_laps). The selector keeps, per
  stored keyframe, its samples in its own camera frame and the ball holding them, valid while the keyframe's
  GlobalKeyframe::revision stays the same (GlobalMap gives a new one at every change); a keyframe whose ball lies
  behind the target camera or outside its image is skipped without projecting a sample. The selection is exactly
  that of projecting every sample (the same arithmetic; the ball only skips keyframes that project none).

  Owns: the samples, about 24 bytes per sample (counted in memoryBytes()).
  Threading: one thread (the mapping thread, with the map it reads).
*/
class VISP_EXPORT ReuseKeyframeSelector
{
public:
  //! The selection of the class comment for the newest keyframe \e target and the window's keyframe ids.
  std::vector<int> select(const GlobalMap &map, const std::vector<int> &windowIds, const ReuseTarget &target,
                          int maxKeyframes);
  //! Forget every keyframe's samples (the map was replaced or cleared).
  void clear() { m_samples.clear(); }
  //! Bytes held by the samples, allocator overhead included.
  double memoryBytes() const;

private:
  struct Samples {
    uint64_t revision = 0; //!< GlobalKeyframe::revision they were read at (0: never)
    bool cornersOnly = true;
    PinholeIntrinsics K;
    std::vector<Eigen::Vector3d> points; //!< in the host camera's frame
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double radius = 0.;
  };
  const Samples &samplesOf(const GlobalKeyframe &kf, const PinholeIntrinsics &K, bool cornersOnly);
  static bool mayProject(const Samples &samples, const SE3d &targetMhost, const ReuseTarget &target);

  std::unordered_map<int, Samples> m_samples;
};

//! ReuseKeyframeSelector::select() with nothing kept from one call to the next.
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
