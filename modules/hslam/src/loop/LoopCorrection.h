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

  A large map revisited again and again is not bent whole. Its graph is a cylinder whose every lap is tied to the laps
  before, and an exact factorisation of it grows far faster than the map: 0.25 s at 1,000 keyframes and 379 s at
  10,000 (bench_loop_scale, lap-linked, 2-core AMD EPYC VM). When the segment holds more than kLoopMaxFreeKeyframes
  stored keyframes and the map's own edges already tie the older ones to the newer (revisits, re-used points, earlier
  loops: at least 20 edges joining keyframes 50 or more apart across the boundary), only the newest
  kLoopMaxFreeKeyframes bend and the older ones move together as one similarity (one vertex). The past and the
  present already agree where they are tied, so a new loop mostly adjusts the present, and a correction costs about
  the same at any size. A past that hangs from the present by the chain alone (one long loop, whose whole span must
  bend) stays free whatever its size: a chain costs 0.75 s at 10,000 keyframes.

  Landmarks seen in metres (AprilTags, map/MetricFrame.h): every sighting of the segment's keyframes is a metric
  constraint of the graph (PoseGraph.h), with one free vertex per landmark, in the loop's correction and in a
  correction of its own when a landmark is seen again after the camera went away (solveLandmarkCorrection(): the
  landmark is the loop, and its metres undo the scale drift between the two visits).

  Threading: a pure function of its inputs.
*/
#ifndef HSLAM_LOOP_LOOP_CORRECTION_H
#define HSLAM_LOOP_LOOP_CORRECTION_H

#include "loop/LandmarkSightings.h"
#include "loop/LoopCloser.h"
#include "loop/PoseGraph.h"

#include <map>
#include <utility>
#include <vector>

namespace hslam
{
/*!
  Stored keyframes a correction bends at most when the map ties its older keyframes to the newer ones (above). Same
  VM: bench_loop_scale's lap-linked correction takes 0.06 / 0.09 / 0.15 s at 1,000 / 3,000 / 10,000 keyframes with
  500; in hslam_many_laps, whose re-used laps tie each keyframe to more of the others, graphs of 500 free keyframes
  took 0.13-0.19 s, of 700 0.5-0.9 s and of 1,000 2.0 s (docs/global-map-and-loops.md).
*/
constexpr size_t kLoopMaxFreeKeyframes = 500;

/*!
  Solve the pose graph of segment \e segment of \e map for \e loop. \e constraints holds the edges of the loops
  corrected before; on success the new loop's kept edge is appended to it (one per loop). \e solution receives (id,
  S_iw) for every stored keyframe of the segment outside the window. False when the optimisation failed or gave a
  non-finite similarity (\e solution then empty). \e maxFreeKeyframes: see kLoopMaxFreeKeyframes.
*/
VISP_EXPORT bool solveLoopCorrection(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                                     std::vector<PoseGraphEdge> &constraints, const DetectedLoop &loop,
                                     std::vector<std::pair<int, Sim3d>> &solution,
                                     const LandmarkSightings &landmarks = LandmarkSightings(),
                                     size_t maxFreeKeyframes = kLoopMaxFreeKeyframes);
/*!
  The correction a landmark seen again asks for: the graph of solveLoopCorrection() (the map's edges, \e constraints
  of the loops before, the window fixed) with \e landmarks' sightings and no new loop. False (and \e solution empty)
  when the sightings do not tie a stored keyframe of the segment to the window, or the optimisation failed.
*/
VISP_EXPORT bool solveLandmarkCorrection(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                                         const std::vector<PoseGraphEdge> &constraints,
                                         const LandmarkSightings &landmarks,
                                         std::vector<std::pair<int, Sim3d>> &solution,
                                         size_t maxFreeKeyframes = kLoopMaxFreeKeyframes);
} // namespace hslam

#endif
