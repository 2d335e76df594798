/*
 * H-SLAM for ViSP.
 */
// LocalMapper, global map part: what leaves the window is kept (lean), and global points come back into the window
// (early adoption, late fusion). H-SLAM paper sec. 3.3; the matching is map/GlobalPointReuse.h.
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include "map/GlobalPointReuse.h"
#include "mapping/AnchorResidual.h"
#include "mapping/PointActivation.h"
#include "tracking/RelocalizationIndex.h"
#include "tracking/Relocalizer.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

namespace hslam
{
namespace
{
//! Gauss-Newton iterations on a re-activated point's inverse depth (as for any activation).
constexpr int kReactivationIterations = 3;

OrbMatcherOptions reuseMatcherOptions(const vpHSlamParameters::GlobalMap &g, int width)
{
  OrbMatcherOptions o;
  o.radiusPx = static_cast<float>(g.reuseRadiusPx * width / kReferenceWidthPx);
  o.maxDistance = g.reuseMaxDistance;
  o.ratio = static_cast<float>(g.reuseRatio);
  o.checkOrientation = true;
  return o;
}

/*!
  The keyframe at \e cMw as a re-use target: the points of \e points (ImmaturePoint or MapPoint) that \e keep
  accepts and that carry a descriptor become its keypoints; \e index maps a keypoint back to its point.
*/
template <typename Point, typename Keep>
ReuseTarget makeReuseTarget(const SE3d &cMw, const PinholeIntrinsics &K, int width, int height, int segment,
                            const std::vector<Point> &points, Keep keep, std::vector<size_t> &index)
{
  ReuseTarget target;
  target.cMw = cMw;
  target.K = K;
  target.width = width;
  target.height = height;
  target.segment = segment;
  // Corners only: re-using every described point (gradient pixels too, without the added corners) was measured
  // worse (fast preset, hybrid, median of 5 runs: Tsukuba 0.334 cm vs 0.276 with corners).
  target.cornersOnly = true;
  index.clear();
  for (size_t i = 0; i < points.size(); ++i) {
    const Point &pt = points[i];
    if (pt.hasOrb && (pt.isCorner || !target.cornersOnly) && keep(pt)) {
      FrameKeypoint k;
      k.u = pt.u;
      k.v = pt.v;
      k.angleDeg = pt.orbAngleDeg;
      k.descriptor = pt.orb;
      target.keypoints.push_back(k);
      index.push_back(i);
    }
  }
  return target;
}

/*!
  A global point enters the window (re-activated or fused into \e mp): its observers become the active point's, and
  its measurements (old host pixel, observers' pixels) are carried, so that the global bundle adjustment still has
  them when the point leaves the window again.
*/
void carryObservations(MapPoint &mp, const GlobalPoint &old, int oldHostId)
{
  auto carry = [&mp](int id, float u, float v) {
    if (!std::isfinite(u) || !std::isfinite(v)) {
      return;
    }
    for (const PixelObservation &o : mp.carried) {
      if (o.keyframeId == id) {
        return;
      }
    }
    mp.carried.push_back({id, u, v});
  };
  carry(oldHostId, old.u, old.v);
  for (size_t i = 0; i < old.observers.size(); ++i) {
    addObserver(mp.observers, old.observers[i]);
    if (i < old.observedAt.size()) {
      carry(old.observers[i], old.observedAt[i][0], old.observedAt[i][1]);
    }
  }
  addObserver(mp.observers, oldHostId);
}

//! Tie \e mp to the stored point \e old of keyframe \e oldHost (mapping/AnchorResidual.h); the anchor replaces the
//! inverse-depth prior in the new host, which carries the same stored estimate.
void anchorToStoredPoint(MapPoint &mp, const GlobalKeyframe &oldHost, const GlobalPoint &old, double varianceScale)
{
  mp.anchorKeyframeId = oldHost.id;
  mp.anchorCMw = oldHost.cMw;
  mp.anchorU = old.u;
  mp.anchorV = old.v;
  mp.anchorIdepth = old.idepth;
  mp.anchorIdepthWeight = 1. / std::max(static_cast<double>(old.idepthVar) * varianceScale, 1e-12);
  mp.idepthPrior = 0.;
  mp.idepthPriorWeight = 0.;
}
} // namespace

int LocalMapper::dropAnchorOutliers()
{
  if (!m_impl->params.globalMap.anchors) {
    return 0; // no point carries an anchor
  }
  const double maxError = m_impl->params.globalMap.anchorMaxErrorPx;
  int dropped = 0;
  for (const KeyframePtr &kf : m_window) {
    for (MapPoint &p : kf->points) {
      if (p.anchorKeyframeId < 0 || p.status != PointStatus::active) {
        continue;
      }
      if (!(anchorPixelError(m_impl->K0, kf->frame->cMw, p.u, p.v, p.idepth, p.anchorCMw, p.anchorU, p.anchorV) <=
            maxError)) {
        p.anchorKeyframeId = -1;
        ++dropped;
      }
    }
  }
  return dropped;
}

void LocalMapper::refreshAnchors()
{
  if (!m_impl->params.globalMap.anchors) {
    return;
  }
  for (const KeyframePtr &kf : m_window) {
    for (MapPoint &p : kf->points) {
      if (p.anchorKeyframeId < 0 || p.status != PointStatus::active) {
        continue;
      }
      const GlobalKeyframe *stored = m_globalMap.find(p.anchorKeyframeId);
      if (stored) {
        p.anchorCMw = stored->cMw;
      } else {
        p.anchorKeyframeId = -1;
      }
    }
  }
}

bool LocalMapper::keepsGlobalMap() const
{
  return keepsGlobalMap(m_impl->params.system.mode);
}

GlobalKeyframe LocalMapper::leanKeyframe(const Keyframe &kf, bool withActivePoints) const
{
  GlobalKeyframe g;
  g.id = kf.id();
  g.frameId = kf.frame->id;
  g.segment = m_segment;
  g.timestamp = kf.frame->timestamp;
  g.exposure = kf.frame->exposure;
  g.cMw = kf.frame->cMw;
  g.affine = kf.frame->affine;
  g.points.reserve(kf.points.size());
  // Observers' poses, for the pixels where they saw each point (window keyframes, else stored ones).
  std::map<int, SE3d> observerPoses;
  for (const KeyframePtr &w : m_window) {
    observerPoses[w->id()] = w->frame->cMw;
  }
  const PinholeIntrinsics &K = m_impl->K0;
  const SE3d wMh = kf.frame->cMw.inverse();
  constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
  for (const MapPoint &p : kf.points) {
    const bool kept = p.status == PointStatus::marginalized ||
                      (withActivePoints && p.status == PointStatus::active && !p.depthFromPrior);
    if (!kept || !(p.idepth > 0.) || !std::isfinite(p.idepthVar)) {
      continue;
    }
    GlobalPoint q;
    q.u = p.u;
    q.v = p.v;
    q.idepth = static_cast<float>(p.idepth);
    q.idepthVar = static_cast<float>(p.idepthVar);
    q.orb = p.orb;
    q.orbAngleDeg = p.orbAngleDeg;
    q.isCorner = p.isCorner;
    q.hasOrb = p.hasOrb;
    q.observers = p.observers;
    q.observers.shrink_to_fit();
    q.observedAt.assign(q.observers.size(), {kUnknown, kUnknown});
    const Eigen::Vector3d wX = wMh * K.unproject(p.u, p.v, p.idepth);
    for (size_t i = 0; i < q.observers.size(); ++i) {
      const int o = q.observers[i];
      auto carried = std::find_if(p.carried.begin(), p.carried.end(),
                                  [o](const PixelObservation &c) { return c.keyframeId == o; });
      if (carried != p.carried.end()) {
        q.observedAt[i] = {carried->u, carried->v};
        continue;
      }
      auto pose = observerPoses.find(o);
      if (pose == observerPoses.end()) {
        const GlobalKeyframe *stored = m_globalMap.find(o);
        if (!stored) {
          continue;
        }
        pose = observerPoses.emplace(o, stored->cMw).first;
      }
      const Eigen::Vector3d cX = pose->second * wX;
      if (cX.z() > 0.) {
        q.observedAt[i] = {static_cast<float>(K.fx * cX.x() / cX.z() + K.cx),
                           static_cast<float>(K.fy * cX.y() / cX.z() + K.cy)};
      }
    }
    g.points.push_back(std::move(q));
  }
  g.points.shrink_to_fit();
  return g;
}

std::vector<PosePoseEdge> LocalMapper::posePoseEdges(const Keyframe &kf,
                                                     const std::vector<PairInformation> &pairs) const
{
  std::vector<PosePoseEdge> edges;
  const int id = kf.id();
  bool linkedBefore = false, linkedAfter = false;
  for (const PairInformation &pair : pairs) {
    PosePoseEdge e;
    e.from = id;
    e.to = pair.otherKeyframeId;
    e.toMfrom = pair.otherMthis;
    e.information = pair.information;
    e.consecutive = std::abs(pair.otherKeyframeId - id) == 1;
    linkedBefore = linkedBefore || pair.otherKeyframeId == id - 1;
    linkedAfter = linkedAfter || pair.otherKeyframeId == id + 1;
    edges.push_back(e);
  }
  // The temporal chain stays whole: a neighbour in time still in the window that shared no residual with this
  // keyframe (a jump) is linked anyway, with no information. Whichever of two consecutive keyframes leaves the
  // window first makes the link, so every consecutive pair is linked once.
  for (const KeyframePtr &other : m_window) {
    const int o = other->id();
    if ((o == id + 1 && !linkedAfter) || (o == id - 1 && !linkedBefore)) {
      PosePoseEdge e;
      e.from = id;
      e.to = o;
      e.toMfrom = other->frame->cMw * kf.frame->cMw.inverse();
      e.consecutive = true;
      edges.push_back(e);
    }
  }
  return edges;
}

void LocalMapper::storeInGlobalMap(const Keyframe &kf, const std::vector<PairInformation> &pairs)
{
  for (const PosePoseEdge &e : posePoseEdges(kf, pairs)) {
    m_globalMap.addPosePoseEdge(e);
  }
  const int id = kf.id();
  if (m_globalMap.add(leanKeyframe(kf, false))) { // culled at once
    if (m_impl->relocalization) {
      m_impl->relocalization->removeKeyframe(id);
    }
    if (m_loop) {
      m_loop->removeKeyframe(id);
    }
  }
}

int LocalMapper::reuseGlobalPoints(Keyframe &newest, int seedKeyframe)
{
  Impl &m = *m_impl;
  ++m_reuse.keyframes;
  if (m_globalMap.keyframes().empty()) {
    return 0;
  }
  const vpHSlamParameters::GlobalMap &g = m.params.globalMap;
  const OrbMatcherOptions options = reuseMatcherOptions(g, m.width);
  std::vector<int> windowIds;
  for (const KeyframePtr &kf : m_window) {
    windowIds.push_back(kf->id());
  }

  // Early adoption: the newest keyframe's corner candidates matched to global points.
  std::vector<size_t> keypointToImmature;
  const ReuseTarget target = makeReuseTarget(
      newest.frame->cMw, m.K0, m.width, m.height, m_segment, newest.immature,
      [](const ImmaturePoint &) { return true; }, keypointToImmature);
  std::vector<int> searched = selectReuseKeyframes(m_globalMap, windowIds, target, g.reuseMaxKeyframes);
  if (seedKeyframe >= 0) {
    // The place a relocalisation found: its stored corners project into the keyframe, but spread over several
    // keyframes, each with too few to pass the overlap test alone (3-lap synthetic loop: 7 samples, 10 needed).
    for (int id : storedNeighbourhood(seedKeyframe)) {
      if (std::find(searched.begin(), searched.end(), id) == searched.end()) {
        searched.push_back(id);
      }
    }
  }
  if (searched.empty()) {
    return 0;
  }
  std::vector<bool> eraseImmature(newest.immature.size(), false);
  int adopted = 0;
  // The stored variance is the window's photometric one (grey-level noise 1, poses held): priorVarianceScale
  // makes the re-used estimate count for less against the new observations.
  std::vector<ReuseMatch> matches = matchGlobalPoints(m_globalMap, searched, target, options);
  for (ReuseMatch &match : matches) {
    match.idepthVar *= g.priorVarianceScale;
  }
  int refused = 0;
  // A keyframe alone in the window (seeded from the stored map) has no other image to refine a point against: the
  // stored estimate is taken as it is, and the next keyframes refine it under its prior.
  const bool alone = m_window.size() == 1;
  for (const ReuseMatch &match : matches) {
    const size_t ii = keypointToImmature[static_cast<size_t>(match.keypoint)];
    const ImmaturePoint &pt = newest.immature[ii];
    const double priorWeight = 1. / std::max(match.idepthVar, 1e-12);
    PointActivationResult r;
    if (alone) {
      r.accepted = true;
      r.idepth = match.idepth;
      r.idepthHessian = priorWeight;
    } else {
      r = m.optimizer.optimizeNewPoint(newest.id(), pt.u, pt.v, match.idepth, pt.patch, pt.patchWeight,
                                       kReactivationIterations, match.idepth, priorWeight);
    }
    // Re-activation keeps the old estimate: the photometric refinement must stay within its prior.
    if (!r.accepted || std::fabs(r.idepth - match.idepth) > g.fusionSigmas * std::sqrt(match.idepthVar)) {
      ++refused;
      continue;
    }
    const GlobalKeyframe *oldHost = m_globalMap.find(match.keyframeId);
    MapPoint mp = PointActivation::makeMapPoint(pt);
    mp.idepth = r.idepth;
    mp.idepthVar = 1. / r.idepthHessian;
    mp.idepthPrior = match.idepth;
    mp.idepthPriorWeight = priorWeight;
    mp.fromGlobalMap = true;
    carryObservations(mp, oldHost->points[match.pointIndex], match.keyframeId);
    if (g.anchors) {
      anchorToStoredPoint(mp, *oldHost, oldHost->points[match.pointIndex], g.priorVarianceScale);
    }
    newest.points.push_back(std::move(mp));
    m_globalMap.absorb(match.keyframeId, match.pointIndex, GlobalPointState::reactivated);
    eraseImmature[ii] = true;
    ++adopted;
  }
  if (adopted > 0) {
    size_t out = 0;
    for (size_t i = 0; i < newest.immature.size(); ++i) {
      if (!eraseImmature[i]) {
        newest.immature[out++] = newest.immature[i];
      }
    }
    newest.immature.resize(out);
  }
  m_reuse.reactivated += adopted;

  // Late fusion: active corners of the window that match a global point whose depth agrees within
  // fusionSigmas standard deviations absorb it (inverse-variance fusion, kept as the point's prior).
  int fused = 0;
  for (const KeyframePtr &host : m_window) {
    std::vector<size_t> keypointToPoint;
    const ReuseTarget t = makeReuseTarget(
        host->frame->cMw, m.K0, m.width, m.height, m_segment, host->points,
        [](const MapPoint &p) { return p.status == PointStatus::active && !p.fromGlobalMap; }, keypointToPoint);
    for (ReuseMatch match : matchGlobalPoints(m_globalMap, searched, t, options)) {
      match.idepthVar *= g.priorVarianceScale;
      MapPoint &p = host->points[keypointToPoint[static_cast<size_t>(match.keypoint)]];
      if (p.fromGlobalMap || std::fabs(match.idepth - p.idepth) > g.fusionSigmas * std::sqrt(p.idepthVar)) {
        continue;
      }
      if (p.depthFromPrior) {
        forgetDepthGuess(p); // the stored point's measured depth replaces the guess made while the camera turned
      }
      double var = 0.;
      p.idepth = fuseInverseVariance(p.idepth, p.idepthVar, match.idepth, match.idepthVar, var);
      p.idepthVar = var;
      // The window re-estimates idepth from its residuals; the global estimate stays as a prior (merged with a
      // prior the point may already have).
      if (p.idepthPriorWeight > 0.) {
        double priorVar = 0.;
        p.idepthPrior =
            fuseInverseVariance(p.idepthPrior, 1. / p.idepthPriorWeight, match.idepth, match.idepthVar, priorVar);
        p.idepthPriorWeight = 1. / priorVar;
      } else {
        p.idepthPrior = match.idepth;
        p.idepthPriorWeight = 1. / std::max(match.idepthVar, 1e-12);
      }
      p.fromGlobalMap = true;
      const GlobalKeyframe *oldHost = m_globalMap.find(match.keyframeId);
      carryObservations(p, oldHost->points[match.pointIndex], match.keyframeId);
      if (g.anchors) {
        anchorToStoredPoint(p, *oldHost, oldHost->points[match.pointIndex], g.priorVarianceScale);
      }
      m_globalMap.absorb(match.keyframeId, match.pointIndex, GlobalPointState::fused);
      ++fused;
    }
  }
  m_reuse.fused += fused;
  VP_HSLAM_LOG(vpHSlamLog::debug,
               "keyframe " << newest.id() << ": " << searched.size() << " stored keyframes searched, " << matches.size()
                           << " of " << target.keypoints.size() << " corners matched, " << refused << " refused, "
                           << adopted << " points re-activated, " << fused << " fused");
  return adopted;
}

LocalMapper::ReuseStatistics LocalMapper::reuseStatistics() const
{
  ReuseStatistics s = m_reuse;
  for (const KeyframePtr &kf : m_window) {
    for (const MapPoint &p : kf->points) {
      if (p.status == PointStatus::active) {
        ++s.windowActive;
        s.windowFromGlobal += p.fromGlobalMap ? 1 : 0;
      }
    }
  }
  s.storedKeyframes = static_cast<int>(m_globalMap.keyframes().size());
  s.culledKeyframes = m_globalMap.culledCount();
  s.storedPoints = m_globalMap.pointCount();
  return s;
}

void LocalMapper::mapPointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> &status) const
{
  points.clear();
  status.clear();
  const PinholeIntrinsics &K = m_impl->K0;
  auto push = [&](const SE3d &wMc, double u, double v, double idepth, int s) {
    const Eigen::Vector3d cX((u - K.cx) / K.fx / idepth, (v - K.cy) / K.fy / idepth, 1. / idepth);
    points.push_back(wMc * cX);
    status.push_back(s);
  };
  for (const KeyframePtr &kf : m_window) {
    const SE3d wMc = kf->frame->cMw.inverse();
    for (const MapPoint &p : kf->points) {
      if (p.idepth > 0. && p.status != PointStatus::outlier) {
        push(wMc, p.u, p.v, p.idepth, p.status == PointStatus::active ? 0 : 1);
      }
    }
  }
  for (const auto &entry : m_globalMap.keyframes()) {
    const SE3d wMc = entry.second.cMw.inverse();
    for (const GlobalPoint &p : entry.second.points) {
      if (p.state == GlobalPointState::stored && p.idepth > 0.f) {
        push(wMc, p.u, p.v, p.idepth, 1);
      }
    }
  }
}
// ------------------------------------------------------------------------------ after a loop correction

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
  if (!p.globalBundleAdjustment || !m_loop) {
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
  ++m_loop->statistics().globalBaStarted;
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
  LoopStatistics &stats = m_loop->statistics();
  stats.globalBaSecondsMax = std::max(stats.globalBaSecondsMax, s.seconds);
  const std::vector<int> moved = applyGlobalBundleJob(job, m_globalMap);
  for (int id : moved) {
    publishStoredKeyframe(id, 1.);
  }
  if (!moved.empty()) {
    ++stats.globalBaApplied;
    stats.globalBaRmsBeforePx = s.rmsBeforePx;
    stats.globalBaRmsAfterPx = s.rmsAfterPx;
  }
  VP_HSLAM_LOG(vpHSlamLog::info, "global bundle adjustment "
                                     << (moved.empty() ? "failed" : "applied") << ": " << s.keyframes << " keyframes ("
                                     << moved.size() << " moved), " << s.points << " points, " << s.observations
                                     << " observations, " << s.iterations << " iterations, reprojection RMS "
                                     << s.rmsBeforePx << " -> " << s.rmsAfterPx << " px, " << s.seconds << " s");
}
} // namespace hslam
