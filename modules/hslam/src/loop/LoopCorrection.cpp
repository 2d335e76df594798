/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopCorrection.h"

#include "loop/PoseGraph.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <set>

namespace hslam
{
namespace
{
//! Co-visibility edges of the pose graph: only strong ones (ORB-SLAM's essential graph: 100 shared points).
constexpr int kEssentialCovisibility = 100;
//! Levenberg-Marquardt iterations of the loop's pose graph (ORB-SLAM: 20).
constexpr int kLoopGraphIterations = 20;
//! Stored neighbours of the candidate tied to the querying side (ORB-SLAM: the connected keyframes).
constexpr size_t kCandidateNeighbours = 5;

//! The vertices: the window's keyframes fixed, the segment's stored ones free (their ids in \e stored).
void addVertices(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses, PoseGraph &graph,
                 std::vector<int> &stored)
{
  for (const auto &w : windowPoses) {
    graph.addVertex(w.first, Sim3d(w.second, 1.), true);
  }
  for (const auto &entry : map.keyframes()) {
    if (entry.second.segment == segment && !windowPoses.count(entry.first)) {
      graph.addVertex(entry.first, Sim3d(entry.second.cMw, 1.), false);
      stored.push_back(entry.first);
    }
  }
}

PoseGraphEdge edge(int i, int j, const Sim3d &Sji)
{
  PoseGraphEdge e;
  e.i = i;
  e.j = j;
  e.Sji = Sji;
  return e;
}

//! Pose of keyframe \e id, stored or in the window.
SE3d poseOf(const GlobalMap &map, const std::map<int, SE3d> &windowPoses, int id)
{
  const auto w = windowPoses.find(id);
  return w != windowPoses.end() ? w->second : map.find(id)->cMw;
}
} // namespace

bool solveLoopCorrection(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                         const std::vector<DetectedLoop> &loops, const DetectedLoop &loop,
                         std::vector<std::pair<int, Sim3d>> &solution)
{
  solution.clear();
  PoseGraph graph;
  std::vector<int> stored;
  addVertices(map, segment, windowPoses, graph, stored);
  auto inGraph = [&](int id) {
    const GlobalKeyframe *g = map.find(id);
    return windowPoses.count(id) > 0 || (g && g->segment == segment);
  };
  auto linksStored = [&](int a, int b) {
    return inGraph(a) && inGraph(b) && !(windowPoses.count(a) && windowPoses.count(b));
  };
  // Pose-pose edges at the current relative poses (ORB-SLAM's essential graph: the uncorrected poses): only the loop
  // edges are in tension. Their measurements from the window (toMfrom) disagree slightly with today's poses, and
  // with them every correction also pulled the whole map towards those older values (Tsukuba there and back: the
  // ATE of slam rose from 0.27 to 0.49 cm with corrections of 2 mm).
  for (const PosePoseEdge &e : map.posePoseEdges()) {
    if (linksStored(e.from, e.to)) {
      graph.addEdgeFromCurrent(e.from, e.to);
    }
  }
  for (const CovisibilityEdge &e : map.covisibilityEdges()) {
    if (e.weight >= kEssentialCovisibility && linksStored(e.a, e.b)) {
      graph.addEdgeFromCurrent(e.a, e.b);
    }
  }
  for (const DetectedLoop &l : loops) {
    if (inGraph(l.candidate) && inGraph(l.keyframe)) {
      graph.addEdge(edge(l.candidate, l.keyframe, l.SkeyframeCandidate));
    }
  }
  // The new loop's connections: the querying keyframe and the window to the candidate's neighbourhood.
  const SE3d cMw = map.find(loop.candidate)->cMw;
  std::vector<int> candidateSide = {loop.candidate};
  for (int n : map.covisibleWith(loop.candidate)) {
    if (candidateSide.size() <= kCandidateNeighbours && inGraph(n) && !windowPoses.count(n)) {
      candidateSide.push_back(n);
    }
  }
  std::vector<int> querySide = {loop.keyframe};
  for (const auto &w : windowPoses) {
    querySide.push_back(w.first);
  }
  const SE3d kMw = poseOf(map, windowPoses, loop.keyframe);
  for (int q : querySide) {
    const Sim3d SqK(poseOf(map, windowPoses, q) * kMw.inverse(), 1.);
    for (int n : candidateSide) {
      if (q == loop.keyframe && n == loop.candidate) {
        continue; // the measured edge itself is already in
      }
      graph.addEdge(edge(n, q, SqK * loop.SkeyframeCandidate * Sim3d(cMw * map.find(n)->cMw.inverse(), 1.)));
    }
  }
  const PoseGraphSummary summary = graph.optimize(kLoopGraphIterations);
  if (!summary.usable) {
    return false;
  }
  for (int id : stored) {
    const Sim3d S = graph.vertex(id);
    if (!S.translation().allFinite() || !(S.scale() > 0.)) {
      solution.clear();
      return false;
    }
    solution.emplace_back(id, S);
  }
  VP_HSLAM_LOG(vpHSlamLog::info, "loop " << loop.keyframe << "-" << loop.candidate << ": pose graph "
                                         << graph.vertexCount() << " vertices, " << graph.edgeCount() << " edges, "
                                         << summary.iterations << " iterations, cost " << summary.initialCost << " -> "
                                         << summary.finalCost);
  return true;
}
} // namespace hslam
