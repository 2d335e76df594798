/*
 * H-SLAM for ViSP.
 */
/*!
  \file LoopCorrection.h
  \brief The pose graph that corrects a segment after a loop (paper sec. 3.4; ORB-SLAM's essential graph).

  Vertices: every stored keyframe of the segment (free, at its stored pose with scale 1) and the window's keyframes
  (fixed: the window's priors tie them, and they hold the gauge). Edges, weighted alike: pose-pose edges between
  stored keyframes or a stored and a window keyframe (as the window measured them), strong co-visibility
  (kEssentialCovisibility shared points, at today's relative poses), one edge for each loop corrected before (its
  measured similarity, an ordinary edge), and the new loop's connections: each keyframe of the querying side (the
  keyframe that closed the loop and the window) to the candidate and its best co-visible keyframes, through the
  measured similarity and each side's current relative poses, so that one edge does not have to bend the whole chain
  alone.

  Threading: a pure function of its inputs.
*/
#ifndef HSLAM_LOOP_LOOP_CORRECTION_H
#define HSLAM_LOOP_LOOP_CORRECTION_H

#include "loop/LoopCloser.h"
#include "loop/PoseGraph.h"

#include <map>
#include <utility>
#include <vector>

namespace hslam
{
/*!
  Solve the pose graph of segment \e segment of \e map for \e loop. \e constraints holds the edges of the loops
  corrected before; on success the new loop's kept edge is appended to it (one per loop). \e solution receives (id,
  S_iw) for every stored keyframe of the segment outside the window. False when the optimisation failed or gave a
  non-finite similarity (\e solution then empty).
*/
VISP_EXPORT bool solveLoopCorrection(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                                     std::vector<PoseGraphEdge> &constraints, const DetectedLoop &loop,
                                     std::vector<std::pair<int, Sim3d>> &solution);
} // namespace hslam

#endif
