/*
 * H-SLAM for ViSP.
 */
// LocalMapper, loop part (system.mode = slam): after each keyframe, bag-of-words candidates among the stored
// keyframes not connected to the window, kept when consistent over loop.consistency keyframes, then verified by
// ORB matching of the two sides' points and a Sim(3) RANSAC (loop/LoopDetector.h, loop/Sim3Solver.h).
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include "loop/GlobalBundleJob.h"
#include "loop/LoopDetector.h"
#include "loop/PoseGraph.h"
#include "loop/Sim3Solver.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <chrono>
#include <set>

namespace hslam
{
namespace
{
//! Stored neighbours of the candidate whose points join its side of the match (ORB-SLAM: the connected keyframes).
constexpr size_t kCandidateNeighbours = 5;
//! Co-visibility edges of the pose graph: only strong ones (ORB-SLAM's essential graph: 100 shared points).
constexpr int kEssentialCovisibility = 100;
//! Levenberg-Marquardt iterations of the loop's pose graph (ORB-SLAM: 20).
constexpr int kLoopGraphIterations = 20;

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
  // Detection time: everything below but the correction (timed on its own).
  const auto t0 = std::chrono::steady_clock::now();
  double correctionMs = 0.;
  struct DetectionTimer {
    LoopStatistics &stats;
    std::chrono::steady_clock::time_point start;
    const double &excluded;
    ~DetectionTimer()
    {
      ++stats.detections;
      stats.detectionMsTotal +=
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() - excluded;
    }
  } timer{m_loops, t0, correctionMs};
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
    // Keyframes whose points the window re-uses now are connected too (their co-visibility is only counted
    // once those points leave the window again): after a loop, re-use links the two sides at once.
    for (const MapPoint &pt : kf->points) {
      if (pt.status == PointStatus::active && pt.fromGlobalMap) {
        connected.insert(pt.observers.begin(), pt.observers.end());
      }
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
    Sim3Estimate estimate;
    std::vector<LoopPointMatch> inliers;
    const auto verificationStart = std::chrono::steady_clock::now();
    try {
      estimate = verifyLoop(newest, candidate, matches, inliers);
      m_loops.verificationMsMax = std::max(
          m_loops.verificationMsMax,
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - verificationStart).count());
    } catch (const vpHSlamException &e) { // a degenerate configuration: this candidate is not a loop
      VP_HSLAM_LOG(vpHSlamLog::warning, "keyframe " << newest.id() << ": loop candidate " << candidate
                                                    << " could not be verified: " << e.getStringMessage());
      continue;
    }
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
    const double rotationDeg = drift.segment<3>(3).norm() * 180. / M_PI;
    if (rotationDeg > p.maxRotationCorrectionDeg) {
      // Odometry drifts a few degrees in rotation, not tens: a correction that large is a place that looks like
      // another (a repeated texture, two alike doors), however consistent its geometry.
      VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << newest.id() << ": loop with keyframe " << candidate
                                                 << " refused: it would rotate the map by " << rotationDeg
                                                 << " degrees");
      ++m_loops.refusedImplausible;
      continue;
    }
    LoopRecord record;
    record.keyframe = newest.id();
    record.candidate = candidate;
    record.inliers = estimate.inlierCount;
    record.scale = estimate.S21.scale();
    record.translationDrift = drift.head<3>().norm();
    m_loops.loops.push_back(record);
    m.keyframeOfLastLoop = m.keyframesInSegment;
    m.loopConsistency.clear();
    m_loopEdges.push_back({candidate, newest.id(), estimate.S21});
    fuseLoopMatches(newest.id(), candidate, inliers);
    bool corrected = false;
    const auto correctionStart = std::chrono::steady_clock::now();
    try {
      corrected = correctLoop(newest, candidate);
    } catch (const vpHSlamException &e) { // nothing is changed before the pose graph succeeded
      VP_HSLAM_LOG(vpHSlamLog::warning, "keyframe " << newest.id() << ": loop with keyframe " << candidate
                                                    << " not corrected: " << e.getStringMessage());
    }
    m_loops.corrected += corrected ? 1 : 0;
    correctionMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - correctionStart).count();
    VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << newest.id() << ": loop with keyframe " << candidate << " ("
                                               << estimate.inlierCount << " inliers, scale " << record.scale
                                               << ", translation correction " << record.translationDrift
                                               << ", rotation correction " << rotationDeg << " degrees)");
    return true;
  }
  return false;
}

Sim3Estimate LocalMapper::verifyLoop(const Keyframe &newest, int candidate, int &matchCount,
                                     std::vector<LoopPointMatch> &inliers) const
{
  inliers.clear();
  const Impl &m = *m_impl;
  const vpHSlamParameters::Loop &p = m.params.loop;
  const PinholeIntrinsics &K = m.K0;
  matchCount = 0;
  // Side A: the window's active corners, in the new keyframe's camera.
  std::vector<LoopPoint> a;
  for (const KeyframePtr &host : m_window) {
    const SE3d newMhost = newest.frame->cMw * host->frame->cMw.inverse();
    for (size_t i = 0; i < host->points.size(); ++i) {
      const MapPoint &pt = host->points[i];
      if (pt.status != PointStatus::active || !pt.hasOrb || !pt.isCorner || !(pt.idepth > 0.) || pt.depthFromPrior) {
        continue;
      }
      LoopPoint lp;
      lp.keyframeId = host->id();
      lp.pointIndex = i;
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
    for (size_t i = 0; i < g->points.size(); ++i) {
      const GlobalPoint &pt = g->points[i];
      if (pt.state != GlobalPointState::stored || !pt.hasOrb || !pt.isCorner || !(pt.idepth > 0.f)) {
        continue;
      }
      LoopPoint lp;
      lp.keyframeId = id;
      lp.pointIndex = i;
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
  Sim3Estimate estimate = estimateSim3Ransac(correspondences, K, K, options);
  if (estimate.success) {
    for (size_t k = 0; k < pairs.size() && k < estimate.inliers.size(); ++k) {
      if (estimate.inliers[k]) {
        inliers.push_back({a[static_cast<size_t>(pairs[k].first)], b[static_cast<size_t>(pairs[k].second)]});
      }
    }
  }
  return estimate;
}

void LocalMapper::fuseLoopMatches(int newestId, int candidate, const std::vector<LoopPointMatch> &inliers)
{
  for (const LoopPointMatch &match : inliers) {
    const LoopPoint &w = match.windowSide;
    const LoopPoint &s = match.storedSide;
    m_globalMap.addObservation(s.keyframeId, s.pointIndex, newestId, static_cast<float>(w.uv.x()),
                               static_cast<float>(w.uv.y()));
    for (const KeyframePtr &host : m_window) {
      if (host->id() != w.keyframeId || w.pointIndex >= host->points.size() || candidate == host->id()) {
        continue;
      }
      MapPoint &p = host->points[w.pointIndex];
      addObserver(p.observers, candidate);
      const bool known = std::any_of(p.carried.begin(), p.carried.end(),
                                     [candidate](const PixelObservation &o) { return o.keyframeId == candidate; });
      if (!known) {
        p.carried.push_back({candidate, static_cast<float>(s.uv.x()), static_cast<float>(s.uv.y())});
      }
    }
  }
}

bool LocalMapper::correctLoop(const Keyframe &newest, int candidate)
{
  Impl &m = *m_impl;
  struct Flag {
    std::atomic<bool> &flag;
    ~Flag() { flag = false; }
  } correcting{m_correctingLoop};
  m_correctingLoop = true;
  // A global bundle adjustment of an earlier loop: written back if it has ended; else it goes on (it works on its own
  // copy) until this correction is known to succeed, and is stopped only then (its keyframes move; a new one follows).
  // A correction that fails must not drop it (the real-time loop test once ended, under AddressSanitizer where the
  // adjustment takes 6 s, with two corrections and none applied).
  collectGlobalBundleAdjustment(false);
  const auto t0 = std::chrono::steady_clock::now();
  PoseGraph graph;
  std::set<int> window;
  for (const KeyframePtr &kf : m_window) {
    graph.addVertex(kf->id(), Sim3d(kf->frame->cMw, 1.), true); // the window's priors tie it: never moved
    window.insert(kf->id());
  }
  std::vector<int> stored;
  for (const auto &entry : m_globalMap.keyframes()) {
    if (entry.second.segment == m_segment && !window.count(entry.first)) {
      graph.addVertex(entry.first, Sim3d(entry.second.cMw, 1.), false);
      stored.push_back(entry.first);
    }
  }
  auto inGraph = [&](int id) {
    const GlobalKeyframe *g = m_globalMap.find(id);
    return window.count(id) > 0 || (g && g->segment == m_segment);
  };
  auto linksStored = [&](int a, int b) { return inGraph(a) && inGraph(b) && !(window.count(a) && window.count(b)); };
  // Edges weighted alike, as ORB-SLAM's essential graph: the window's photometric information is far larger
  // than what a loop edge can be given, and would pin the old side.
  for (const PosePoseEdge &e : m_globalMap.posePoseEdges()) {
    if (linksStored(e.from, e.to)) {
      PoseGraphEdge g;
      g.i = e.from;
      g.j = e.to;
      g.Sji = Sim3d(e.toMfrom, 1.);
      graph.addEdge(g);
    }
  }
  for (const CovisibilityEdge &e : m_globalMap.covisibilityEdges()) {
    if (e.weight >= kEssentialCovisibility && linksStored(e.a, e.b)) {
      graph.addEdgeFromCurrent(e.a, e.b);
    }
  }
  for (const LoopEdge &loop : m_loopEdges) {
    if (inGraph(loop.candidate) && inGraph(loop.keyframe)) {
      PoseGraphEdge g;
      g.i = loop.candidate;
      g.j = loop.keyframe;
      g.Sji = loop.SkeyframeCandidate;
      graph.addEdge(g);
    }
  }
  // The new loop joins both neighbourhoods (ORB-SLAM's loop connections): every window keyframe to the candidate
  // and its best co-visible stored keyframes, through the measured similarity and each side's current relative
  // poses, so that one edge does not have to bend the whole chain alone.
  const GlobalKeyframe *c = m_globalMap.find(candidate);
  std::vector<int> candidateSide = {candidate};
  for (int n : m_globalMap.covisibleWith(candidate)) {
    if (candidateSide.size() <= kCandidateNeighbours && inGraph(n) && !window.count(n)) {
      candidateSide.push_back(n);
    }
  }
  const Sim3d SnewCandidate = m_loopEdges.back().SkeyframeCandidate;
  for (const KeyframePtr &w : m_window) {
    const Sim3d SwNew(w->frame->cMw * newest.frame->cMw.inverse(), 1.);
    for (int n : candidateSide) {
      const GlobalKeyframe *g = m_globalMap.find(n);
      if (!g || (w->id() == newest.id() && n == candidate)) {
        continue; // the measured edge itself is already in
      }
      PoseGraphEdge e;
      e.i = n;
      e.j = w->id();
      e.Sji = SwNew * SnewCandidate * Sim3d(c->cMw * g->cMw.inverse(), 1.);
      graph.addEdge(e);
    }
  }
  const PoseGraphSummary summary = graph.optimize(kLoopGraphIterations);
  if (!summary.usable) {
    VP_HSLAM_LOG(vpHSlamLog::warning, "keyframe " << newest.id() << ": loop with keyframe " << candidate
                                                  << " not corrected (pose graph failed)");
    return false;
  }
  // The map follows its hosts: a keyframe's new pose is the rigid part of its similarity, and its points' inverse
  // depths are multiplied by the scale (X_camera' = X_camera / s); frames tracked against it follow (scale).
  std::vector<Sim3d> solution; // read (and checked) before anything changes
  for (int id : stored) {
    solution.push_back(graph.vertex(id));
    if (!solution.back().translation().allFinite() || !(solution.back().scale() > 0.)) {
      VP_HSLAM_LOG(vpHSlamLog::warning, "keyframe " << newest.id() << ": loop not corrected (non-finite solution)");
      return false;
    }
  }
  m.globalBa.cancel(); // its result would undo this correction
  for (size_t k = 0; k < stored.size(); ++k) {
    const int id = stored[k];
    GlobalKeyframe *g = m_globalMap.find(id);
    const Sim3d &S = solution[k];
    const double s = S.scale();
    g->cMw = SE3d(S.unitQuaternion(), S.translation() / s);
    for (GlobalPoint &p : g->points) {
      p.idepth = static_cast<float>(p.idepth * s);
      p.idepthVar = static_cast<float>(p.idepthVar * s * s);
    }
    publishStoredKeyframe(id, s);
  }
  m_loops.lastCorrectionMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  m_loops.correctionMsMax = std::max(m_loops.correctionMsMax, m_loops.lastCorrectionMs);
  VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << newest.id() << ": loop corrected, " << stored.size()
                                             << " stored keyframes moved (pose graph " << graph.vertexCount()
                                             << " vertices, " << graph.edgeCount() << " edges, " << summary.iterations
                                             << " iterations, cost " << summary.initialCost << " -> "
                                             << summary.finalCost << "), " << m_loops.lastCorrectionMs << " ms");
  startGlobalBundleAdjustment();
  return true;
}

void LocalMapper::publishStoredKeyframe(int id, double scale)
{
  Impl &m = *m_impl;
  const GlobalKeyframe *g = m_globalMap.find(id);
  KeyframeState state;
  state.id = id;
  state.wMc = g->cMw.inverse();
  state.inWindow = false;
  state.scale = scale;
  m.marginalizedStates.push_back(state);
  RelocalizationKeyframe points;
  if (!m.relocalization || !m.relocalization->keyframePoints(id, points)) {
    return;
  }
  points.wX.clear();
  points.descriptors.clear();
  for (const GlobalPoint &p : g->points) {
    if (p.hasOrb && p.isCorner && p.idepth > 0.f) {
      points.wX.push_back(state.wMc * m.K0.unproject(p.u, p.v, p.idepth));
      points.descriptors.push_back(p.orb);
    }
  }
  m.relocalization->setKeyframePoints(id, std::move(points.wX), std::move(points.descriptors));
}

void LocalMapper::startGlobalBundleAdjustment()
{
  Impl &m = *m_impl;
  const vpHSlamParameters::Loop &p = m.params.loop;
  if (!p.globalBundleAdjustment) {
    return;
  }
  std::map<int, SE3d> windowPoses;
  for (const KeyframePtr &kf : m_window) {
    windowPoses[kf->id()] = kf->frame->cMw;
  }
  GlobalBundleOptions options;
  options.maxIterations = p.globalBaIterations;
  options.huberPx = p.globalBaHuberPx;
  std::unique_ptr<GlobalBundleJob> job =
      makeGlobalBundleJob(m_globalMap, m_segment, windowPoses, m.K0, options, p.globalBaPointsPerKeyframe);
  ++m_loops.globalBaStarted;
  if (m.params.system.deterministic) {
    job->run(); // in order, inside track(): the same output run to run
    finishGlobalBundleAdjustment(*job);
  } else {
    m.globalBa.start(std::move(job)); // a job of an earlier loop still running is cancelled
  }
}

bool LocalMapper::collectGlobalBundleAdjustment(bool wait)
{
  Impl &m = *m_impl;
  if (!m.globalBa.running() || (!wait && !m.globalBa.finished())) {
    return false;
  }
  std::unique_ptr<GlobalBundleJob> job = m.globalBa.take();
  finishGlobalBundleAdjustment(*job);
  return true;
}

void LocalMapper::finishGlobalBundleAdjustment(const GlobalBundleJob &job)
{
  const GlobalBundleSummary &s = job.summary;
  m_loops.globalBaSecondsMax = std::max(m_loops.globalBaSecondsMax, s.seconds);
  const std::vector<int> moved = applyGlobalBundleJob(job, m_globalMap);
  for (int id : moved) {
    publishStoredKeyframe(id, 1.);
  }
  if (!moved.empty()) {
    ++m_loops.globalBaApplied;
    m_loops.globalBaRmsBeforePx = s.rmsBeforePx;
    m_loops.globalBaRmsAfterPx = s.rmsAfterPx;
  }
  VP_HSLAM_LOG(vpHSlamLog::info, "global bundle adjustment "
                                     << (moved.empty() ? "failed" : "applied") << ": " << s.keyframes << " keyframes ("
                                     << moved.size() << " moved), " << s.points << " points, " << s.observations
                                     << " observations, " << s.iterations << " iterations, reprojection RMS "
                                     << s.rmsBeforePx << " -> " << s.rmsAfterPx << " px, " << s.seconds << " s");
}
} // namespace hslam
