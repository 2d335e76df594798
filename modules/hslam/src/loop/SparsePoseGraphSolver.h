/*
 * H-SLAM for ViSP.
 */
/*!
  \file SparsePoseGraphSolver.h
  \brief A Levenberg-Marquardt solver for large Sim(3) pose graphs (private to loop/: PoseGraph).

  What it is for: a loop correction in a map of thousands of keyframes. Analytic Jacobians of the edge error
  log(S_ji Si Sj^-1) under left updates (first order in the error, see linearize()), the normal equations accumulated
  7x7 block by 7x7 block into a fixed sparsity pattern, free vertices numbered once in the approximate minimum
  degree order of their block graph, and Eigen's simplicial LDL^T factorisation (symbolic analysis once). Marquardt's
  scaling (H + damping diag(H)) and Nielsen's damping update; the termination tests and the first damping are those
  of Ceres' defaults. At 10,000 keyframes it solves the loop benchmark's graph in 0.7 s where Ceres (automatic
  differentiation, its own J^T J) took 5.1 s (test/loop/bench_loop_scale.cpp, docs/global-map-and-loops.md).

  Threading: a pure function.
*/
#ifndef HSLAM_LOOP_SPARSE_POSE_GRAPH_SOLVER_H
#define HSLAM_LOOP_SPARSE_POSE_GRAPH_SOLVER_H

#include "loop/PoseGraph.h"

#include <utility>
#include <vector>

namespace hslam
{
/*!
  Minimise 0.5 sum |W (log(S_ji Si Sj^-1))|^2 over the vertices \e S whose \e fixed flag is false, for at most
  \e maxIterations steps (accepted or not). \e ends gives, per edge, the positions of its i and j in \e S. \e S is
  updated in place; the summary's usable is false when the start or the result is not finite (ms is left to the
  caller). \e sightings (PoseGraph.h) join the landmark and keyframe vertices at \e sightingEnds; their robust
  cost is 0.5 weight^2 c^2 log(1 + |r|^2 / c^2), as Ceres' scaled Cauchy loss.
*/
PoseGraphSummary solveSparsePoseGraph(std::vector<Sim3d> &S, const std::vector<bool> &fixed,
                                      const std::vector<PoseGraphEdge> &edges,
                                      const std::vector<std::pair<size_t, size_t>> &ends, int maxIterations,
                                      const std::vector<PoseGraphSighting> &sightings = {},
                                      const std::vector<std::pair<size_t, size_t>> &sightingEnds = {});
} // namespace hslam

#endif
