/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopCorrection.h"

#include "loop/PoseGraph.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>
#include <limits>
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
//! Stored keyframes apart from which an edge is a revisit, not the window's own measurement (it holds 7).
constexpr size_t kRevisitSpan = 50;
//! Revisit edges across the boundary from which the past counts as tied to the present (one loop adds one).
constexpr size_t kMinRevisitTies = 20;
//! Vertex id of the past, which moves as one.
constexpr int kPastVertex = std::numeric_limits<int>::min();
/*!
  Standard deviations of a landmark sighting: the tag detector's measured accuracy (docs/metric-tag-frame.md: 0.3 %
  of the range, 1-1.5 degrees at 45-60 pixels; map/MetricFit.cpp uses the same).
*/
constexpr double kSightingRangeShare = 0.003;
constexpr double kSightingRotationRad = 1.5 * M_PI / 180.;
/*!
  Weight of a whitened sighting against the graph's edges, whose information is the identity (radians, map units,
  log-scale): as though an edge were good to about kSightingWeight radian and unit. Measured on the tag room over
  five point budgets (docs/metric-tag-frame.md): 1e-1 let the detections' noise into the map (Sim(3)-aligned ATE
  8-9.5 mm against 4.5-6 mm without the constraints), 1e-2 and 1e-3 both improved it (3.3-4.2 and 3.5-4.6 mm).
  Beyond kSightingRobustScale standard deviations a sighting counts less and less
  (Cauchy): a flipped pose of a small tag seen face-on is off by tens of degrees.
*/
constexpr double kSightingWeight = 1e-2;
constexpr double kSightingRobustScale = 3.;
//! Vertex id of landmark \e l (ids >= 0): below every keyframe id, above kPastVertex.
int landmarkVertex(int l)
{
  return -2 - l;
}

//! The keyframes a correction's graph holds: the window's (fixed), the segment's stored ones (free), and among the
//! latter, when the map is large and ties its past to its present, the older ones held together (the past).
struct SegmentKeyframes {
  const GlobalMap &map;
  int segment;
  const std::map<int, SE3d> &windowPoses;
  //! Stored keyframes with a smaller id move together, as one similarity (kPastVertex); none when INT_MIN.
  int firstFree = std::numeric_limits<int>::min();

  bool holds(int id) const
  {
    const GlobalKeyframe *g = map.find(id);
    return windowPoses.count(id) > 0 || (g && g->segment == segment);
  }
  bool inPast(int id) const { return id < firstFree && !windowPoses.count(id) && holds(id); }
  //! An edge that can move something: both ends held, not both in the window or both in the past.
  bool linksStored(int a, int b) const
  {
    return holds(a) && holds(b) && !(windowPoses.count(a) && windowPoses.count(b)) && !(inPast(a) && inPast(b));
  }
  //! Pose of keyframe \e id, stored or in the window.
  SE3d pose(int id) const
  {
    const auto w = windowPoses.find(id);
    return w != windowPoses.end() ? w->second : map.find(id)->cMw;
  }
  //! The segment's stored keyframes outside the window, in increasing id (the order they were stored in).
  std::vector<int> stored() const
  {
    std::vector<int> ids;
    for (const auto &entry : map.keyframes()) {
      if (entry.second.segment == segment && !windowPoses.count(entry.first)) {
        ids.push_back(entry.first);
      }
    }
    return ids;
  }
};

/*!
  Where a large map's correction stops bending it: the id of the oldest of the \e maxFreeKeyframes newest stored
  keyframes, when at least kMinRevisitTies of the map's edges join a keyframe older than that to a newer one at least
  kRevisitSpan stored keyframes apart (places revisited, re-used points, loops: the past and the present already agree
  there, and a new loop only adjusts the present). INT_MIN, everything free, otherwise: a map that size, or one whose
  past hangs from the present by the chain alone (one long loop, where the whole span must bend), or a small map.
*/
int firstFreeKeyframe(const SegmentKeyframes &keyframes, const std::vector<CovisibilityEdge> &covisibility,
                      const std::vector<PoseGraphEdge> &constraints, size_t maxFreeKeyframes)
{
  const std::vector<int> ids = keyframes.stored();
  maxFreeKeyframes = std::max<size_t>(maxFreeKeyframes, 1);
  if (ids.size() <= maxFreeKeyframes) {
    return std::numeric_limits<int>::min();
  }
  const int boundary = ids[ids.size() - maxFreeKeyframes];
  // Rank in storage order; the window's keyframes are the newest.
  const auto rank = [&](int id) {
    return keyframes.windowPoses.count(id)
               ? ids.size()
               : static_cast<size_t>(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin());
  };
  size_t ties = 0;
  const auto count = [&](int a, int b) {
    if (!keyframes.holds(a) || !keyframes.holds(b)) {
      return;
    }
    const size_t ra = rank(a), rb = rank(b);
    const bool crosses =
        (a < boundary && !keyframes.windowPoses.count(a)) != (b < boundary && !keyframes.windowPoses.count(b));
    if (crosses && std::max(ra, rb) - std::min(ra, rb) > kRevisitSpan) {
      ++ties;
    }
  };
  for (const PosePoseEdge &e : keyframes.map.posePoseEdges()) {
    count(e.from, e.to);
  }
  for (const CovisibilityEdge &e : covisibility) {
    if (e.weight >= kEssentialCovisibility) {
      count(e.a, e.b);
    }
  }
  for (const PoseGraphEdge &c : constraints) {
    count(c.i, c.j);
  }
  return ties >= kMinRevisitTies ? boundary : std::numeric_limits<int>::min();
}

PoseGraphEdge edge(int i, int j, const Sim3d &Sji)
{
  PoseGraphEdge e;
  e.i = i;
  e.j = j;
  e.Sji = Sji;
  return e;
}

/*!
  The pose graph of one correction. The past, when there is one, is a single free vertex kPastVertex, the similarity
  T^-1 that moves every past keyframe as one (S_pw = S_pw0 T^-1): an edge (p, j) from a past keyframe p measures
  S_jp, and its residual log(S_jp S_pw0 T^-1 S_jw^-1) is that of an edge (kPastVertex, j) measuring S_jp S_pw0. An
  edge into the past is turned round first (the same measurement, its residual seen from the other end). Edges
  between two past keyframes are constant under that motion and left out.
*/
class CorrectionGraph
{
public:
  explicit CorrectionGraph(const SegmentKeyframes &keyframes) : m_keyframes(keyframes), m_stored(keyframes.stored())
  {
    for (const auto &w : keyframes.windowPoses) {
      m_graph.addVertex(w.first, Sim3d(w.second, 1.), true);
    }
    for (int id : m_stored) {
      if (keyframes.inPast(id)) {
        ++m_pastKeyframes;
      } else {
        m_graph.addVertex(id, Sim3d(keyframes.map.find(id)->cMw, 1.), false);
      }
    }
  }

  void add(PoseGraphEdge e)
  {
    if (m_keyframes.inPast(e.i) && m_keyframes.inPast(e.j)) {
      return;
    }
    if (m_keyframes.inPast(e.j)) {
      std::swap(e.i, e.j);
      e.Sji = e.Sji.inverse();
    }
    if (m_keyframes.inPast(e.i)) {
      e.Sji = e.Sji * Sim3d(m_keyframes.pose(e.i), 1.);
      e.i = pastVertex();
    }
    m_graph.addEdge(e);
  }
  //! An edge at the current relative pose of \e a and \e b.
  void addFromCurrent(int a, int b)
  {
    if (m_keyframes.inPast(a) || m_keyframes.inPast(b)) {
      add(edge(a, b, Sim3d(m_keyframes.pose(b), 1.) * Sim3d(m_keyframes.pose(a), 1.).inverse()));
    } else {
      m_graph.addEdgeFromCurrent(a, b);
    }
  }

  /*!
    The sightings of held keyframes, one free vertex per landmark placed by its newest sighting. Returns how many
    were added.
  */
  size_t addSightings(const LandmarkSightings &landmarks)
  {
    if (!landmarks.usable()) {
      return 0;
    }
    size_t added = 0;
    for (auto it = landmarks.sightings.rbegin(); it != landmarks.sightings.rend(); ++it) {
      const LandmarkSighting &s = *it;
      if (!m_keyframes.holds(s.keyframe) || s.landmark < 0 || !(s.range > 0.)) {
        continue;
      }
      const int l = landmarkVertex(s.landmark);
      if (!m_landmarks.count(l)) { // the newest sighting places it: S_lw = S_kl^-1 S_kw, the map's scale now
        const Sim3d Skl(s.cMl.unitQuaternion(), s.cMl.translation() / landmarks.metresPerUnit,
                        1. / landmarks.metresPerUnit);
        m_graph.addVertex(l, Skl.inverse() * Sim3d(m_keyframes.pose(s.keyframe), 1.), false);
        m_landmarks.insert(l);
      }
      PoseGraphSighting e;
      e.landmark = l;
      e.keyframe = s.keyframe;
      if (m_keyframes.inPast(s.keyframe)) { // moves with the past: S_kw = S_kw0 T^-1
        e.Akw = Sim3d(m_keyframes.pose(s.keyframe), 1.);
        e.keyframe = pastVertex();
      }
      e.cMl = s.cMl;
      e.sqrtInformation.setIdentity();
      e.sqrtInformation.topLeftCorner<3, 3>() /= kSightingRotationRad;
      e.sqrtInformation.bottomRightCorner<3, 3>() /= kSightingRangeShare * s.range;
      e.robustScale = kSightingRobustScale;
      e.weight = kSightingWeight;
      m_graph.addSighting(e);
      ++added;
    }
    return added;
  }

  PoseGraph &graph() { return m_graph; }
  size_t pastKeyframes() const { return m_pastKeyframes; }

  //! The solved similarity of every stored keyframe into \e solution; false (and empty) when one is not usable.
  bool readSolution(std::vector<std::pair<int, Sim3d>> &solution) const
  {
    const auto usable = [](const Sim3d &S) { return S.translation().allFinite() && S.scale() > 0.; };
    const Sim3d past = m_pastInGraph ? m_graph.vertex(kPastVertex) : Sim3d();
    if (!usable(past)) {
      return false;
    }
    for (int id : m_stored) {
      const Sim3d S = m_keyframes.inPast(id) ? Sim3d(m_keyframes.pose(id), 1.) * past : m_graph.vertex(id);
      if (!usable(S)) {
        solution.clear();
        return false;
      }
      solution.emplace_back(id, S);
    }
    return true;
  }

private:
  //! The past's vertex, added with the first edge or sighting that reaches it.
  int pastVertex()
  {
    if (!m_pastInGraph) {
      m_graph.addVertex(kPastVertex, Sim3d(), false);
      m_pastInGraph = true;
    }
    return kPastVertex;
  }

  const SegmentKeyframes &m_keyframes;
  const std::vector<int> m_stored; //!< the segment's stored keyframes outside the window, in increasing id
  size_t m_pastKeyframes = 0;
  PoseGraph m_graph;
  bool m_pastInGraph = false;
  std::set<int> m_landmarks; //!< landmark vertices added
};

/*!
  What the map and the loops before measured: pose-pose edges as the window measured them (the relative pose of its
  last linearisation), strong co-visibility at today's relative poses, and every loop corrected so far (one edge
  each, \e constraints), so each correction is the batch solution of the window's measurements and all loops. At
  today's poses instead, an early correction stayed baked into the chain: on the synthetic outward loop the median
  ATE over five budgets rose from 0.016 to 0.023 m (on the real sequences played there and back the two were within
  5 %, either way).
*/
void addMeasuredEdges(const SegmentKeyframes &keyframes, const std::vector<CovisibilityEdge> &covisibility,
                      const std::vector<PoseGraphEdge> &constraints, CorrectionGraph &graph)
{
  for (const PosePoseEdge &e : keyframes.map.posePoseEdges()) {
    if (keyframes.linksStored(e.from, e.to)) {
      graph.add(edge(e.from, e.to, Sim3d(e.toMfrom, 1.)));
    }
  }
  for (const CovisibilityEdge &e : covisibility) {
    if (e.weight >= kEssentialCovisibility && keyframes.linksStored(e.a, e.b)) {
      graph.addFromCurrent(e.a, e.b);
    }
  }
  for (const PoseGraphEdge &c : constraints) {
    if (keyframes.holds(c.i) && keyframes.holds(c.j)) {
      graph.add(c);
    }
  }
}

/*!
  The new loop's connections: each keyframe of the querying side (the keyframe that closed the loop and the window)
  to the candidate and its best co-visible keyframes, through the measured similarity and each side's current
  relative poses. Returns the first, the measured similarity itself (candidate to querying keyframe).
*/
PoseGraphEdge addLoopEdges(const SegmentKeyframes &keyframes, const DetectedLoop &loop, CorrectionGraph &graph)
{
  const SE3d cMw = keyframes.map.find(loop.candidate)->cMw;
  std::vector<int> candidateSide = {loop.candidate};
  for (int n : keyframes.map.covisibleWith(loop.candidate)) {
    if (candidateSide.size() <= kCandidateNeighbours && keyframes.holds(n) && !keyframes.windowPoses.count(n)) {
      candidateSide.push_back(n);
    }
  }
  std::vector<int> querySide = {loop.keyframe};
  for (const auto &w : keyframes.windowPoses) {
    querySide.push_back(w.first);
  }
  const SE3d kMw = keyframes.pose(loop.keyframe);
  std::vector<PoseGraphEdge> added;
  for (int q : querySide) {
    const Sim3d SqK(keyframes.pose(q) * kMw.inverse(), 1.);
    for (int n : candidateSide) {
      added.push_back(
          edge(n, q, SqK * loop.SkeyframeCandidate * Sim3d(cMw * keyframes.map.find(n)->cMw.inverse(), 1.)));
      graph.add(added.back());
    }
  }
  return added.front();
}
} // namespace

bool solveLoopCorrection(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                         std::vector<PoseGraphEdge> &constraints, const DetectedLoop &loop,
                         std::vector<std::pair<int, Sim3d>> &solution, const LandmarkSightings &landmarks,
                         size_t maxFreeKeyframes)
{
  solution.clear();
  SegmentKeyframes keyframes{map, segment, windowPoses};
  const std::vector<CovisibilityEdge> covisibility = map.covisibilityEdges();
  keyframes.firstFree = firstFreeKeyframe(keyframes, covisibility, constraints, maxFreeKeyframes);
  CorrectionGraph correction(keyframes);
  addMeasuredEdges(keyframes, covisibility, constraints, correction);
  const PoseGraphEdge measured = addLoopEdges(keyframes, loop, correction);
  correction.addSightings(landmarks);
  PoseGraph &graph = correction.graph();
  const PoseGraphSummary summary = graph.optimize(kLoopGraphIterations);
  if (!summary.usable || !correction.readSolution(solution)) {
    return false;
  }
  // What later corrections keep of this loop: its measured similarity between its two keyframes, as an ordinary
  // edge. The loop's other edges are that measurement carried to the neighbours through relative poses the graph
  // holds anyway. Keeping all of them (8 x 6 a loop) filled the factorisation of a long run in, and their weight
  // together on every later correction tore the loops' keyframes from their neighbours; the same weight on the one
  // edge did it too: the candidate's similarity followed the loop's measured scale while its neighbours followed the
  // chain, so its points and the frames tracked against it were rescaled apart from the rest, the next loops measured
  // scales of 0.5-1.8 (0.01-36 with all 48 edges), and the ATE of hslam_many_laps went from 3-7 cm to 0.5 m by 950
  // stored keyframes. As one ordinary edge the loops' scales stayed within 0.96-1.04 and the ATE at 2.4-4.5 cm to 811
  // keyframes (docs/global-map-and-loops.md).
  constraints.push_back(measured);
  VP_HSLAM_LOG(vpHSlamLog::info, "loop " << loop.keyframe << "-" << loop.candidate << ": pose graph "
                                         << graph.vertexCount() << " vertices (" << correction.pastKeyframes()
                                         << " past keyframes held together), " << graph.edgeCount() << " edges, "
                                         << summary.iterations << " iterations, cost " << summary.initialCost << " -> "
                                         << summary.finalCost << ", " << summary.ms << " ms");
  return true;
}

bool solveLandmarkCorrection(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                             const std::vector<PoseGraphEdge> &constraints, const LandmarkSightings &landmarks,
                             std::vector<std::pair<int, Sim3d>> &solution, size_t maxFreeKeyframes)
{
  solution.clear();
  SegmentKeyframes keyframes{map, segment, windowPoses};
  // Something to correct: a landmark seen from the window and from a stored keyframe of the segment.
  std::set<int> seenNow, seenBefore;
  for (const LandmarkSighting &s : landmarks.sightings) {
    if (windowPoses.count(s.keyframe)) {
      seenNow.insert(s.landmark);
    } else if (keyframes.holds(s.keyframe)) {
      seenBefore.insert(s.landmark);
    }
  }
  const bool tied = std::any_of(seenNow.begin(), seenNow.end(), [&](int l) { return seenBefore.count(l) > 0; });
  if (!landmarks.usable() || !tied) {
    return false;
  }
  const std::vector<CovisibilityEdge> covisibility = map.covisibilityEdges();
  keyframes.firstFree = firstFreeKeyframe(keyframes, covisibility, constraints, maxFreeKeyframes);
  CorrectionGraph correction(keyframes);
  addMeasuredEdges(keyframes, covisibility, constraints, correction);
  const size_t sightings = correction.addSightings(landmarks);
  if (sightings == 0) {
    return false;
  }
  PoseGraph &graph = correction.graph();
  const PoseGraphSummary summary = graph.optimize(kLoopGraphIterations);
  if (!summary.usable || !correction.readSolution(solution)) {
    return false;
  }
  VP_HSLAM_LOG(vpHSlamLog::info, "landmark correction: pose graph "
                                     << graph.vertexCount() << " vertices (" << correction.pastKeyframes()
                                     << " past keyframes held together), " << graph.edgeCount() << " edges, "
                                     << sightings << " sightings, " << summary.iterations << " iterations, cost "
                                     << summary.initialCost << " -> " << summary.finalCost << ", " << summary.ms
                                     << " ms");
  return true;
}
} // namespace hslam
