/*
 * H-SLAM for ViSP.
 */
// LocalMapper, global map part: what leaves the window is kept (lean), and global points come back into the window
// (early adoption, late fusion). H-SLAM paper sec. 3.3; the matching is map/GlobalPointReuse.h.
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include "map/GlobalPointReuse.h"
#include "mapping/PointActivation.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! Gauss-Newton iterations on a re-activated point's inverse depth (as for any activation).
constexpr int kReactivationIterations = 3;
//! The reuse radius is given at 640 px width; other widths scale it.
constexpr double kReferenceWidthPx = 640.;

OrbMatcherOptions reuseMatcherOptions(const vpHSlamParameters::GlobalMap &g, int width)
{
  OrbMatcherOptions o;
  o.radiusPx = static_cast<float>(g.reuseRadiusPx * width / kReferenceWidthPx);
  o.maxDistance = g.reuseMaxDistance;
  o.ratio = static_cast<float>(g.reuseRatio);
  o.checkOrientation = true;
  return o;
}
} // namespace

bool LocalMapper::keepsGlobalMap() const
{
  return m_impl->params.system.mode != vpHSlamParameters::modeVoStrict;
}

void LocalMapper::storeInGlobalMap(const Keyframe &kf, const std::vector<PairInformation> &pairs)
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
  for (const MapPoint &p : kf.points) {
    if (p.status != PointStatus::marginalized || !(p.idepth > 0.) || !std::isfinite(p.idepthVar)) {
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
    g.points.push_back(std::move(q));
  }
  g.points.shrink_to_fit();
  bool consecutiveLinked = false;
  for (const PairInformation &pair : pairs) {
    PosePoseEdge e;
    e.from = kf.id();
    e.to = pair.otherKeyframeId;
    e.toMfrom = pair.otherMthis;
    e.information = pair.information;
    e.consecutive = pair.otherKeyframeId == kf.id() + 1;
    consecutiveLinked = consecutiveLinked || e.consecutive;
    m_globalMap.addPosePoseEdge(e);
  }
  const int id = kf.id();
  if (!consecutiveLinked) {
    // The next keyframe shared no residual (a jump): the temporal link still joins them, with no information.
    for (const KeyframePtr &other : m_window) {
      if (other->id() == id + 1) {
        PosePoseEdge e;
        e.from = id;
        e.to = id + 1;
        e.toMfrom = other->frame->cMw * kf.frame->cMw.inverse();
        e.consecutive = true;
        m_globalMap.addPosePoseEdge(e);
      }
    }
  }
  if (m_globalMap.add(std::move(g)) && m_impl->relocalization) {
    m_impl->relocalization->removeKeyframe(id);
  }
}

int LocalMapper::reuseGlobalPoints(Keyframe &newest)
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
  ReuseTarget target;
  target.cMw = newest.frame->cMw;
  target.K = m.K0;
  target.width = m.width;
  target.height = m.height;
  target.segment = m_segment;
  // Corners only: re-using every described point (gradient pixels too, without the added corners) was measured
  // worse (fast preset, hybrid, median of 5 runs: Tsukuba 0.334 cm vs 0.276 with corners).
  target.cornersOnly = true;
  std::vector<size_t> keypointToImmature;
  for (size_t i = 0; i < newest.immature.size(); ++i) {
    const ImmaturePoint &pt = newest.immature[i];
    if (pt.hasOrb && (pt.isCorner || !target.cornersOnly)) {
      FrameKeypoint k;
      k.u = pt.u;
      k.v = pt.v;
      k.angleDeg = pt.orbAngleDeg;
      k.descriptor = pt.orb;
      target.keypoints.push_back(k);
      keypointToImmature.push_back(i);
    }
  }
  const std::vector<int> searched = selectReuseKeyframes(m_globalMap, windowIds, target, g.reuseMaxKeyframes);
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
  for (const ReuseMatch &match : matches) {
    const size_t ii = keypointToImmature[static_cast<size_t>(match.keypoint)];
    const ImmaturePoint &pt = newest.immature[ii];
    const double priorWeight = 1. / std::max(match.idepthVar, 1e-12);
    const PointActivationResult r =
        m.optimizer.optimizeNewPoint(newest.id(), pt.u, pt.v, match.idepth, pt.patch, pt.patchWeight,
                                     kReactivationIterations, match.idepth, priorWeight);
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
    mp.observers = oldHost->points[match.pointIndex].observers;
    addObserver(mp.observers, match.keyframeId);
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
    ReuseTarget t;
    t.cMw = host->frame->cMw;
    t.K = m.K0;
    t.width = m.width;
    t.height = m.height;
    t.segment = m_segment;
    t.cornersOnly = target.cornersOnly;
    std::vector<size_t> keypointToPoint;
    for (size_t i = 0; i < host->points.size(); ++i) {
      const MapPoint &p = host->points[i];
      if (p.status == PointStatus::active && p.hasOrb && (p.isCorner || !t.cornersOnly) && !p.fromGlobalMap) {
        FrameKeypoint k;
        k.u = p.u;
        k.v = p.v;
        k.angleDeg = p.orbAngleDeg;
        k.descriptor = p.orb;
        t.keypoints.push_back(k);
        keypointToPoint.push_back(i);
      }
    }
    for (ReuseMatch match : matchGlobalPoints(m_globalMap, searched, t, options)) {
      match.idepthVar *= g.priorVarianceScale;
      MapPoint &p = host->points[keypointToPoint[static_cast<size_t>(match.keypoint)]];
      if (p.fromGlobalMap || std::fabs(match.idepth - p.idepth) > g.fusionSigmas * std::sqrt(p.idepthVar)) {
        continue;
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
      for (int o : oldHost->points[match.pointIndex].observers) {
        addObserver(p.observers, o);
      }
      addObserver(p.observers, match.keyframeId);
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
} // namespace hslam
