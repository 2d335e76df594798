/*
 * H-SLAM for ViSP.
 */
/*!
  \file OrbMatcher.h
  \brief Guided ORB matching: map points projected into a new frame are matched to the frame's keypoints within a
  search radius (paper section 3.2 step 1; ORB-SLAM2's SearchByProjection rules).

  A projected point is compared with the keypoints inside a radius around its predicted pixel (a grid makes the
  search local); the best keypoint is kept when its Hamming distance is at most maxDistance and, when a second
  candidate exists, clearly better than it (best < ratio * second). A keypoint keeps only its best point. Finally
  the rotation-consistency check keeps the matches whose keypoint-minus-point orientation difference falls in the
  three most populated bins of a 30-bin histogram (a frame rotates as a whole, so consistent matches agree on it).

  Threading: a matcher holds its grid and is used from one thread; build one per frame.
*/
#ifndef HSLAM_FEATURES_ORB_MATCHER_H
#define HSLAM_FEATURES_ORB_MATCHER_H

#include "features/BinaryDescriptor.h"

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
//! A keypoint of the frame being matched.
struct FrameKeypoint {
  float u = 0.f, v = 0.f; //!< pixel
  float angleDeg = 0.f;   //!< ORB orientation, degrees
  OrbDescriptor descriptor;
};

//! A map point projected into the frame.
struct ProjectedPoint {
  float u = 0.f, v = 0.f; //!< predicted pixel
  float angleDeg = 0.f;   //!< orientation of its descriptor in its host keyframe, degrees
  OrbDescriptor descriptor;
};

//! Settings (defaults: ORB-SLAM2's tracking matcher and ARCHITECTURE.md).
struct OrbMatcherOptions {
  float radiusPx = 15.f;        //!< search radius around the predicted pixel
  int maxDistance = 100;        //!< Hamming distance accepted at most (ORB-SLAM2 TH_HIGH)
  float ratio = 0.9f;           //!< best must be below ratio x second best (ORB-SLAM2 projection search: 0.9)
  bool checkOrientation = true; //!< rotation-consistency histogram
  int histogramBins = 30;       //!< orientation histogram bins (ORB-SLAM2 HISTO_LENGTH)
  int cellSizePx = 16;          //!< grid cell of the keypoint index
};

//! One match: index of the projected point and of the keypoint, and their Hamming distance.
struct OrbMatch {
  int point = -1;
  int keypoint = -1;
  int distance = 0;
};

class VISP_EXPORT OrbMatcher
{
public:
  //! Index the keypoints of a frame of size width x height.
  OrbMatcher(const std::vector<FrameKeypoint> &keypoints, int width, int height,
             const OrbMatcherOptions &options = OrbMatcherOptions());

  //! Matches of \e points (each point at most once, each keypoint at most once), in point order.
  std::vector<OrbMatch> matchProjected(const std::vector<ProjectedPoint> &points) const;
  //! Same with another radius (the tracker widens it when too few points match).
  std::vector<OrbMatch> matchProjected(const std::vector<ProjectedPoint> &points, float radiusPx) const;

private:
  void keypointsNear(float u, float v, float radius, std::vector<int> &out) const;

  const std::vector<FrameKeypoint> &m_keypoints;
  OrbMatcherOptions m_options;
  int m_cols = 0, m_rows = 0;
  std::vector<std::vector<int>> m_cells;
};
} // namespace hslam

#endif
