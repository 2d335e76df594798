/*
 * H-SLAM for ViSP.
 */
/*!
  \file LoopDetector.h
  \brief Loop detection pieces (paper sec. 3.4; ORB-SLAM2's LoopClosing::DetectLoop and ComputeSim3 rules):
  temporal consistency of candidate groups, and the 3D-3D ORB matches that the Sim(3) verification needs.

  LoopConsistency: a candidate's group is the candidate and its co-visible keyframes. A group is consistent with a
  group of the previous query when they share a keyframe; its count is then that group's plus one (else 0). A
  candidate is accepted when its count reaches requiredConsistency (ORB-SLAM: 3). A query with no candidate resets
  the memory. matchLoopPoints(): every point of side B (the loop candidate and its neighbours) is compared with
  every point of side A (the current keyframe's window points) by Hamming distance; a pair is kept when the best
  distance is at most maxDistance, below ratio times the second best, and the A point is not claimed by a closer B
  point (each point at most once).

  Threading: LoopConsistency is used from one thread; matchLoopPoints() is a pure function.
*/
#ifndef HSLAM_LOOP_LOOP_DETECTOR_H
#define HSLAM_LOOP_LOOP_DETECTOR_H

#include "features/BinaryDescriptor.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <set>
#include <utility>
#include <vector>

namespace hslam
{
class VISP_EXPORT LoopConsistency
{
public:
  explicit LoopConsistency(int requiredConsistency = 3) : m_required(requiredConsistency) {}

  /*!
    One query's candidates, each with its group (the candidate and its co-visible keyframes). Returns the
    candidates accepted now (their group consistent over requiredConsistency consecutive queries), in input order.
  */
  std::vector<int> update(const std::vector<std::pair<int, std::vector<int>>> &candidateGroups);
  void clear() { m_groups.clear(); }

private:
  int m_required;
  std::vector<std::pair<std::set<int>, int>> m_groups; //!< previous query's groups and their counts
};

//! A map point offered to loop matching: its position in its side's reference camera, pixel there, descriptor.
struct LoopPoint {
  Eigen::Vector3d X = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  OrbDescriptor orb;
  int keyframeId = -1;     //!< the point's host (window or stored keyframe)
  size_t pointIndex = 0;   //!< its index among the host's points
  std::uint8_t octave = 0; //!< pyramid level it was detected at (0: level 0, or not a keypoint)
};

//! A verified loop match (a Sim(3) inlier): the same point seen from both ends of the loop.
struct LoopPointMatch {
  LoopPoint querySide;     //!< X, uv: in the keyframe that closed the loop
  LoopPoint candidateSide; //!< X, uv: in the candidate keyframe
};

//! Index pairs (into a, into b) of the ORB matches (see file comment).
VISP_EXPORT std::vector<std::pair<int, int>>
matchLoopPoints(const std::vector<LoopPoint> &a, const std::vector<LoopPoint> &b, int maxDistance, double ratio);
} // namespace hslam

#endif
