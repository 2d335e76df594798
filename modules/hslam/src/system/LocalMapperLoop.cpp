/*
 * H-SLAM for ViSP.
 */
// LocalMapper, loop part (system.mode = slam): after each keyframe, bag-of-words candidates among the stored
// keyframes not connected to the window, kept when consistent over loop.consistency keyframes, then verified by
// ORB matching of the two sides' points and a Sim(3) RANSAC (loop/LoopDetector.h, loop/Sim3Solver.h).
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include "loop/LoopDetector.h"
#include "loop/Sim3Solver.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <set>

namespace hslam
{
namespace
{
//! Stored neighbours of the candidate whose points join its side of the match (ORB-SLAM: the connected keyframes).
constexpr size_t kCandidateNeighbours = 5;

bool projectPoint(const PinholeIntrinsics &K, const Eigen::Vector3d &X, Eigen::Vector2d &uv)
{
  if (!(X.z() > 0.)) {
    return false;
  }
  uv = Eigen::Vector2d(K.fx * X.x() / X.z() + K.cx, K.fy * X.y() / X.z() + K.cy);
  return true;
}
} // namespace

bool LocalMapper::detectLoop(const Keyframe &newest)
{
  Impl &m = *m_impl;
  const vpHSlamParameters::Loop &p = m.params.loop;
  if (!m.relocalization || m.keyframesInSegment - m.keyframeOfLastLoop < p.minKeyframesBetween) {
    return false;
  }
  const KeyframeDatabase &database = m.relocalization->database();
  BowVector bow;
  if (!database.vectorOf(newest.id(), bow)) {
    return false;
  }
  // Keyframes connected to the new one: the window and whatever is co-visible with it.
  std::set<int> connected;
  std::vector<int> neighbours;
  for (const KeyframePtr &kf : m_window) {
    connected.insert(kf->id());
    if (kf->id() != newest.id()) {
      neighbours.push_back(kf->id());
    }
  }
  for (const KeyframePtr &kf : m_window) {
    for (int c : m_globalMap.covisibleWith(kf->id())) {
      connected.insert(c);
    }
  }
  const std::vector<double> scores = database.scoresWith(bow, neighbours);
  if (scores.empty()) {
    return false;
  }
  KeyframeDatabase::Query query;
  query.minScore = *std::min_element(scores.begin(), scores.end());
  query.excluded = [&](int id) {
    const GlobalKeyframe *g = m_globalMap.find(id);
    return connected.count(id) > 0 || !g || g->segment != m_segment;
  };
  query.covisible = [&](int id) { return m_globalMap.covisibleWith(id); };
  std::vector<std::pair<int, std::vector<int>>> groups;
  for (const KeyframeDatabase::Candidate &c : database.query(bow, query)) {
    groups.emplace_back(c.id, m_globalMap.covisibleWith(c.id));
  }
  const std::vector<int> accepted = groups.empty() ? std::vector<int>() : m.loopConsistency.update(groups);
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << newest.id() << ": loop query, " << connected.size()
                                              << " connected keyframes excluded, min score " << query.minScore << ", "
                                              << groups.size() << " candidates, " << accepted.size() << " consistent");
  if (groups.empty()) {
    m.loopConsistency.clear();
    return false;
  }
  for (int candidate : accepted) {
    ++m_loops.candidatesVerified;
    int matches = 0;
    const Sim3Estimate estimate = verifyLoop(newest, candidate, matches);
    VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << newest.id() << ": loop candidate " << candidate << ", " << matches
                                               << " ORB matches, " << estimate.inlierCount << " Sim(3) inliers"
                                               << (estimate.success ? " (accepted)" : " (rejected)"));
    if (!estimate.success) {
      continue;
    }
    // The loop's correction of the current estimate: how far the new keyframe is from where the candidate's side
    // says it is (S_Kc measured against the poses' S_Kc).
    const GlobalKeyframe *c = m_globalMap.find(candidate);
    const Sim3d current(newest.frame->cMw * c->cMw.inverse(), 1.);
    const Sim3d::Tangent drift = (estimate.S21 * current.inverse()).log();
    LoopRecord record;
    record.keyframe = newest.id();
    record.candidate = candidate;
    record.inliers = estimate.inlierCount;
    record.scale = estimate.S21.scale();
    record.translationDrift = drift.head<3>().norm();
    m_loops.loops.push_back(record);
    m.keyframeOfLastLoop = m.keyframesInSegment;
    m.loopConsistency.clear();
    VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << newest.id() << ": loop with keyframe " << candidate << " ("
                                               << estimate.inlierCount << " inliers, scale " << record.scale
                                               << ", translation correction " << record.translationDrift << ")");
    return true;
  }
  return false;
}

Sim3Estimate LocalMapper::verifyLoop(const Keyframe &newest, int candidate, int &matchCount) const
{
  const Impl &m = *m_impl;
  const vpHSlamParameters::Loop &p = m.params.loop;
  const PinholeIntrinsics &K = m.K0;
  matchCount = 0;
  // Side A: the window's active corners, in the new keyframe's camera.
  std::vector<LoopPoint> a;
  for (const KeyframePtr &host : m_window) {
    const SE3d newMhost = newest.frame->cMw * host->frame->cMw.inverse();
    for (const MapPoint &pt : host->points) {
      if (pt.status != PointStatus::active || !pt.hasOrb || !pt.isCorner || !(pt.idepth > 0.)) {
        continue;
      }
      LoopPoint lp;
      lp.X = newMhost * (Eigen::Vector3d((pt.u - K.cx) / K.fx, (pt.v - K.cy) / K.fy, 1.) / pt.idepth);
      lp.orb = pt.orb;
      if (projectPoint(K, lp.X, lp.uv)) {
        a.push_back(lp);
      }
    }
  }
  // Side B: the stored corners of the candidate and of its best co-visible stored keyframes, in its camera.
  const GlobalKeyframe *c = m_globalMap.find(candidate);
  std::vector<int> side = {candidate};
  std::vector<std::pair<int, int>> ranked; // (weight, id)
  for (const CovisibilityEdge &e : m_globalMap.covisibilityEdges()) {
    if (e.a == candidate || e.b == candidate) {
      ranked.emplace_back(e.weight, e.a == candidate ? e.b : e.a);
    }
  }
  std::sort(ranked.rbegin(), ranked.rend());
  for (size_t i = 0; i < ranked.size() && side.size() <= kCandidateNeighbours; ++i) {
    if (m_globalMap.find(ranked[i].second)) {
      side.push_back(ranked[i].second);
    }
  }
  std::vector<LoopPoint> b;
  for (int id : side) {
    const GlobalKeyframe *g = m_globalMap.find(id);
    const SE3d cMg = c->cMw * g->cMw.inverse();
    for (const GlobalPoint &pt : g->points) {
      if (pt.state != GlobalPointState::stored || !pt.hasOrb || !pt.isCorner || !(pt.idepth > 0.f)) {
        continue;
      }
      LoopPoint lp;
      lp.X = cMg * (Eigen::Vector3d((pt.u - K.cx) / K.fx, (pt.v - K.cy) / K.fy, 1.) / static_cast<double>(pt.idepth));
      lp.orb = pt.orb;
      if (projectPoint(K, lp.X, lp.uv)) {
        b.push_back(lp);
      }
    }
  }
  const std::vector<std::pair<int, int>> pairs = matchLoopPoints(a, b, p.matchMaxDistance, p.matchRatio);
  matchCount = static_cast<int>(pairs.size());
  Sim3Estimate failed;
  if (matchCount < p.minMatches) {
    return failed;
  }
  std::vector<Sim3Correspondence> correspondences;
  for (const auto &pr : pairs) {
    Sim3Correspondence s;
    s.X1 = b[static_cast<size_t>(pr.second)].X; // candidate camera
    s.uv1 = b[static_cast<size_t>(pr.second)].uv;
    s.X2 = a[static_cast<size_t>(pr.first)].X; // new keyframe camera
    s.uv2 = a[static_cast<size_t>(pr.first)].uv;
    correspondences.push_back(s);
  }
  Sim3RansacOptions options;
  options.minInliers = p.minInliers;
  options.maxReprojectionPx = p.ransacThresholdPx;
  options.seed = static_cast<unsigned int>(newest.id());
  return estimateSim3Ransac(correspondences, K, K, options);
}
} // namespace hslam
