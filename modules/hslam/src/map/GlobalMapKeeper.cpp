/*
 * H-SLAM for ViSP.
 */
#include "map/GlobalMapKeeper.h"

#include "map/GlobalPointReuse.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <set>

namespace hslam
{
namespace
{
//! Relocalisation and re-use search a stored keyframe together with the keyframes this many ids before and after it.
constexpr int kNeighboursInTime = 2;

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

GlobalMap::Options mapOptions(const vpHSlamParameters &params)
{
  const vpHSlamParameters::GlobalMap &g = params.globalMap;
  GlobalMap::Options o;
  o.covisibilityMinShared = g.covisibilityMinShared;
  o.cullObservedShare = g.cullObservedShare;
  o.cullMinObservers = g.cullMinObservers;
  o.windowSize = params.mapper.windowSize;
  return o;
}
} // namespace

GlobalMapKeeper::GlobalMapKeeper(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height)
    : m_params(params), m_K0(K0), m_width(width), m_height(height), m_map(mapOptions(params))
{
}

// ------------------------------------------------------------------------------------------------ storing

GlobalKeyframe GlobalMapKeeper::leanKeyframe(const Keyframe &kf, const std::vector<KeyframePtr> &window,
                                             bool withActivePoints) const
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
  for (const KeyframePtr &w : window) {
    observerPoses[w->id()] = w->frame->cMw;
  }
  const PinholeIntrinsics &K = m_K0;
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
        const GlobalKeyframe *stored = m_map.find(o);
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

std::vector<PosePoseEdge> GlobalMapKeeper::posePoseEdges(const Keyframe &kf, const std::vector<KeyframePtr> &window,
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
  for (const KeyframePtr &other : window) {
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

bool GlobalMapKeeper::store(const Keyframe &kf, const std::vector<KeyframePtr> &window,
                            const std::vector<PairInformation> &pairs)
{
  for (const PosePoseEdge &e : posePoseEdges(kf, window, pairs)) {
    m_map.addPosePoseEdge(e);
  }
  return m_map.add(leanKeyframe(kf, window, false));
}

std::vector<int> GlobalMapKeeper::storedNeighbourhood(int id) const
{
  std::vector<int> ids = m_map.covisibleWith(id);
  for (int n = id - kNeighboursInTime; n <= id + kNeighboursInTime; ++n) {
    ids.push_back(n);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<int> out;
  for (int n : ids) {
    const GlobalKeyframe *kf = m_map.find(n);
    if (kf && !kf->culled) {
      out.push_back(n);
    }
  }
  return out;
}

int GlobalMapKeeper::closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) const
{
  const Eigen::Vector3d centre = cMw.inverse().translation();
  int best = -1;
  double bestDistance = 0.;
  for (int id : keyframeIds) {
    const GlobalKeyframe *kf = m_map.find(id);
    if (!kf) {
      continue;
    }
    const double d = (kf->cMw.inverse().translation() - centre).norm();
    if (best < 0 || d < bestDistance) {
      best = id;
      bestDistance = d;
    }
  }
  return best;
}

// ------------------------------------------------------------------------------------------------ re-use

int GlobalMapKeeper::reuse(Keyframe &newest, const std::vector<KeyframePtr> &window, int seedKeyframe,
                           const ReuseRefinement &refinement)
{
  ++m_stats.keyframes;
  if (m_map.keyframes().empty()) {
    return 0;
  }
  std::vector<int> windowIds;
  for (const KeyframePtr &kf : window) {
    windowIds.push_back(kf->id());
  }
  // The stored keyframes searched: those whose points project into the newest keyframe (overlap test).
  std::vector<size_t> keypointToImmature;
  const ReuseTarget target = makeReuseTarget(
      newest.frame->cMw, m_K0, m_width, m_height, m_segment, newest.immature,
      [](const ImmaturePoint &) { return true; }, keypointToImmature);
  std::vector<int> searched = m_selector.select(m_map, windowIds, target, m_params.globalMap.reuseMaxKeyframes);
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
  const int adopted = adopt(newest, window.size() == 1, searched, target, keypointToImmature, refinement);
  m_stats.reactivated += adopted;
  const int fused = fuse(window, searched);
  m_stats.fused += fused;
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << newest.id() << ": " << searched.size()
                                              << " stored keyframes searched, " << adopted << " points re-activated, "
                                              << fused << " fused");
  return adopted;
}

int GlobalMapKeeper::adopt(Keyframe &newest, bool alone, const std::vector<int> &searched, const ReuseTarget &target,
                           const std::vector<size_t> &keypointToImmature, const ReuseRefinement &refinement)
{
  const vpHSlamParameters::GlobalMap &g = m_params.globalMap;
  std::vector<bool> eraseImmature(newest.immature.size(), false);
  int adopted = 0;
  // The stored variance is the window's photometric one (grey-level noise 1, poses held): priorVarianceScale
  // makes the re-used estimate count for less against the new observations.
  std::vector<ReuseMatch> matches = matchGlobalPoints(m_map, searched, target, reuseMatcherOptions(g, m_width));
  for (ReuseMatch &match : matches) {
    match.idepthVar *= g.priorVarianceScale;
  }
  int refused = 0;
  // A keyframe alone in the window (seeded from the stored map) has no other image to refine a point against: the
  // stored estimate is taken as it is, and the next keyframes refine it under its prior.
  for (const ReuseMatch &match : matches) {
    const size_t ii = keypointToImmature[static_cast<size_t>(match.keypoint)];
    const ImmaturePoint &pt = newest.immature[ii];
    const double priorWeight = 1. / std::max(match.idepthVar, 1e-12);
    ReuseRefinement::Result r;
    if (alone) {
      r.accepted = true;
      r.idepth = match.idepth;
      r.idepthHessian = priorWeight;
    } else {
      r = refinement.refine(newest.id(), pt, match.idepth, priorWeight);
    }
    // Re-activation keeps the old estimate: the photometric refinement must stay within its prior.
    if (!r.accepted || std::fabs(r.idepth - match.idepth) > g.fusionSigmas * std::sqrt(match.idepthVar)) {
      ++refused;
      continue;
    }
    const GlobalKeyframe *oldHost = m_map.find(match.keyframeId);
    MapPoint mp = refinement.activate(pt);
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
    m_map.absorb(match.keyframeId, match.pointIndex, GlobalPointState::reactivated);
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
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << newest.id() << ": " << matches.size() << " of "
                                              << target.keypoints.size() << " corners matched, " << refused
                                              << " refused");
  return adopted;
}

int GlobalMapKeeper::fuse(const std::vector<KeyframePtr> &window, const std::vector<int> &searched)
{
  // Late fusion: active corners of the window that match a global point whose depth agrees within
  // fusionSigmas standard deviations absorb it (inverse-variance fusion, kept as the point's prior).
  const vpHSlamParameters::GlobalMap &g = m_params.globalMap;
  const OrbMatcherOptions options = reuseMatcherOptions(g, m_width);
  int fused = 0;
  for (const KeyframePtr &host : window) {
    std::vector<size_t> keypointToPoint;
    const ReuseTarget t = makeReuseTarget(
        host->frame->cMw, m_K0, m_width, m_height, m_segment, host->points,
        [](const MapPoint &p) { return p.status == PointStatus::active && !p.fromGlobalMap; }, keypointToPoint);
    for (ReuseMatch match : matchGlobalPoints(m_map, searched, t, options)) {
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
      const GlobalKeyframe *oldHost = m_map.find(match.keyframeId);
      carryObservations(p, oldHost->points[match.pointIndex], match.keyframeId);
      if (g.anchors) {
        anchorToStoredPoint(p, *oldHost, oldHost->points[match.pointIndex], g.priorVarianceScale);
      }
      m_map.absorb(match.keyframeId, match.pointIndex, GlobalPointState::fused);
      ++fused;
    }
  }
  return fused;
}

GlobalMapKeeper::Statistics GlobalMapKeeper::statistics(const std::vector<KeyframePtr> &window) const
{
  Statistics s = m_stats;
  for (const KeyframePtr &kf : window) {
    for (const MapPoint &p : kf->points) {
      if (p.status == PointStatus::active) {
        ++s.windowActive;
        s.windowFromGlobal += p.fromGlobalMap ? 1 : 0;
      }
    }
  }
  s.storedKeyframes = static_cast<int>(m_map.keyframes().size());
  s.culledKeyframes = m_map.culledCount();
  s.storedPoints = m_map.pointCount();
  return s;
}

void GlobalMapKeeper::pointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> &status) const
{
  for (const auto &entry : m_map.keyframes()) {
    const SE3d wMc = entry.second.cMw.inverse();
    for (const GlobalPoint &p : entry.second.points) {
      if (p.state == GlobalPointState::stored && p.idepth > 0.f) {
        const Eigen::Vector3d cX((p.u - m_K0.cx) / m_K0.fx / p.idepth, (p.v - m_K0.cy) / m_K0.fy / p.idepth,
                                 1. / p.idepth);
        points.push_back(wMc * cX);
        status.push_back(1);
      }
    }
  }
}

// ------------------------------------------------------------------------------------------------ map files

void GlobalMapKeeper::snapshot(const std::vector<KeyframePtr> &window,
                               const std::function<std::vector<PairInformation>(int)> &pairsOf,
                               std::vector<GlobalKeyframe> &keyframes, std::vector<PosePoseEdge> &edges) const
{
  keyframes.clear();
  edges = m_map.posePoseEdges();
  for (const auto &entry : m_map.keyframes()) {
    keyframes.push_back(entry.second);
  }
  const float minQuality = static_cast<float>(m_params.mapper.minTraceQuality);
  for (const KeyframePtr &kf : window) {
    keyframes.push_back(leanKeyframe(*kf, window, true));
    // The newest keyframes' points are mostly still immature: those whose depth interval has converged are kept too
    // (variance: the half interval squared), or the end of the run has no map to locate a camera in.
    for (const ImmaturePoint &pt : kf->immature) {
      if (!pt.hasOrb || !hasConvergedDepth(pt, minQuality)) {
        continue;
      }
      GlobalPoint q;
      q.u = pt.u;
      q.v = pt.v;
      q.idepth = 0.5f * (pt.idepthMin + pt.idepthMax);
      q.idepthVar = 0.25f * (pt.idepthMax - pt.idepthMin) * (pt.idepthMax - pt.idepthMin);
      q.orb = pt.orb;
      q.orbAngleDeg = pt.orbAngleDeg;
      q.isCorner = pt.isCorner;
      q.hasOrb = true;
      keyframes.back().points.push_back(std::move(q));
    }
    // Each window pair once: from the older keyframe to the newer one.
    std::vector<PairInformation> pairs = pairsOf(kf->id());
    pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                               [&kf](const PairInformation &p) { return p.otherKeyframeId < kf->id(); }),
                pairs.end());
    for (const PosePoseEdge &e : posePoseEdges(*kf, window, pairs)) {
      if (e.to > e.from) { // a link back in time is the older window keyframe's link forward
        edges.push_back(e);
      }
    }
  }
  // In id order whatever left the window first: the same map always gives the same file.
  std::sort(keyframes.begin(), keyframes.end(),
            [](const GlobalKeyframe &a, const GlobalKeyframe &b) { return a.id < b.id; });
  // A segment whose window was dropped (tracking lost) leaves observers and edges naming keyframes nobody holds.
  std::set<int> held;
  for (const GlobalKeyframe &kf : keyframes) {
    held.insert(kf.id);
  }
  for (GlobalKeyframe &kf : keyframes) {
    for (GlobalPoint &p : kf.points) {
      dropObservers(p, [&held](int id) { return held.count(id) == 0; });
    }
  }
  edges.erase(std::remove_if(edges.begin(), edges.end(),
                             [&held](const PosePoseEdge &e) { return !held.count(e.from) || !held.count(e.to); }),
              edges.end());
}

void GlobalMapKeeper::restore(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges)
{
  int lastSegment = -1;
  for (const GlobalKeyframe &kf : keyframes) {
    lastSegment = std::max(lastSegment, kf.segment);
  }
  m_map.restore(std::move(keyframes), std::move(edges));
  m_selector.clear();
  m_segment = std::max(m_segment, lastSegment + 1);
}

void GlobalMapKeeper::reset()
{
  m_map.clear();
  m_selector.clear();
  m_stats = Statistics();
  m_segment = 0;
}
} // namespace hslam
