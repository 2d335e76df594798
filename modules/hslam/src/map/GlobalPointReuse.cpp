/*
 * H-SLAM for ViSP.
 */
#include "map/GlobalPointReuse.h"

#include "common/HeapBytes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>

namespace hslam
{
namespace
{
//! Keyframe selection looks at every this-th stored corner (the overlap estimate need not be exact).
constexpr size_t kSampleStride = 4;
//! A keyframe not linked by the graph needs this many sampled corners in the target image to be searched.
constexpr int kMinProjectedSamples = 10;
//! Projected points must land this far inside the image (ORB's patch needs room; so did the keypoints').
constexpr double kBorderPx = 16.;

//! A point in the target camera's frame lands in front of it and inside the image's border.
bool projectsInside(const Eigen::Vector3d &X, const ReuseTarget &target)
{
  if (!(X.z() > 0.)) {
    return false;
  }
  const Eigen::Vector2d uv = target.K.project(X);
  return uv.x() >= kBorderPx && uv.y() >= kBorderPx && uv.x() < target.width - kBorderPx &&
         uv.y() < target.height - kBorderPx;
}
} // namespace

bool ReuseKeyframeSelector::mayProject(const Samples &samples, const SE3d &targetMhost, const ReuseTarget &target)
{
  // The samples lie in a ball; a ball behind the camera or wholly outside one side plane of the image's frustum (the
  // border included) projects none of them. The radius is widened a little so that rounding never refuses a sample
  // that the exact test would take.
  const Eigen::Vector3d c = targetMhost * samples.centre;
  const double r = samples.radius * (1. + 1e-6) + 1e-12;
  if (c.z() + r <= 0.) {
    return false;
  }
  const PinholeIntrinsics &K = target.K;
  // u >= border  <=>  fx x - (border - cx) z >= 0 in front of the camera; likewise for the three other sides.
  const std::array<Eigen::Vector3d, 4> planes = {
      Eigen::Vector3d(K.fx, 0., K.cx - kBorderPx), Eigen::Vector3d(-K.fx, 0., target.width - kBorderPx - K.cx),
      Eigen::Vector3d(0., K.fy, K.cy - kBorderPx), Eigen::Vector3d(0., -K.fy, target.height - kBorderPx - K.cy)};
  for (const Eigen::Vector3d &n : planes) {
    if (n.dot(c) + r * n.norm() < 0.) {
      return false;
    }
  }
  return true;
}

const ReuseKeyframeSelector::Samples &ReuseKeyframeSelector::samplesOf(const GlobalKeyframe &kf,
                                                                       const PinholeIntrinsics &K, bool cornersOnly)
{
  Samples &s = m_samples[kf.id];
  if (s.revision == kf.revision && s.cornersOnly == cornersOnly && s.K.fx == K.fx && s.K.fy == K.fy && s.K.cx == K.cx &&
      s.K.cy == K.cy) {
    return s;
  }
  s.revision = kf.revision;
  s.cornersOnly = cornersOnly;
  s.K = K;
  s.points.clear();
  size_t corner = 0;
  for (const GlobalPoint &p : kf.points) {
    if (p.state != GlobalPointState::stored || !p.hasOrb || (cornersOnly && !p.isCorner) ||
        (corner++ % kSampleStride) != 0 || !(p.idepth > 0.f)) {
      continue;
    }
    s.points.push_back(K.unproject(p.u, p.v, static_cast<double>(p.idepth)));
  }
  s.points.shrink_to_fit();
  s.centre.setZero();
  for (const Eigen::Vector3d &X : s.points) {
    s.centre += X;
  }
  s.centre /= std::max<double>(1., static_cast<double>(s.points.size()));
  s.radius = 0.;
  for (const Eigen::Vector3d &X : s.points) {
    s.radius = std::max(s.radius, (X - s.centre).norm());
  }
  return s;
}

std::vector<int> ReuseKeyframeSelector::select(const GlobalMap &map, const std::vector<int> &windowIds,
                                               const ReuseTarget &target, int maxKeyframes)
{
  // The stored keyframes co-visible with the window: the window's own rows of the co-visibility graph. Every edge of
  // the map was walked before, 20 % of hslam_many_laps' time at 2,000 stored keyframes (the same set).
  std::set<int> linked;
  for (int w : windowIds) {
    for (int n : map.covisibleWith(w)) {
      if (std::find(windowIds.begin(), windowIds.end(), n) == windowIds.end()) {
        linked.insert(n);
      }
    }
  }
  if (m_samples.size() > 2 * map.keyframes().size() + 64) {
    m_samples.clear(); // keyframes that left the map (a reset, a loaded map): forget their samples
  }
  std::vector<std::pair<int, int>> scored; // (projected samples, id)
  for (const auto &entry : map.keyframes()) {
    const GlobalKeyframe &kf = entry.second;
    if (kf.segment != target.segment) {
      continue;
    }
    const Samples &samples = samplesOf(kf, target.K, target.cornersOnly);
    const SE3d targetMhost = target.cMw * kf.cMw.inverse();
    if (samples.points.empty() || !mayProject(samples, targetMhost, target)) {
      continue;
    }
    int projected = 0;
    for (const Eigen::Vector3d &hostX : samples.points) {
      projected += projectsInside(targetMhost * hostX, target) ? 1 : 0;
    }
    if (projected >= kMinProjectedSamples || (projected > 0 && linked.count(kf.id))) {
      scored.emplace_back(projected, kf.id);
    }
  }
  // Most overlap first; ties: the newest keyframe (larger id) first, so the order is deterministic.
  std::sort(scored.begin(), scored.end(), [](const std::pair<int, int> &a, const std::pair<int, int> &b) {
    return a.first != b.first ? a.first > b.first : a.second > b.second;
  });
  std::vector<int> out;
  for (size_t i = 0; i < scored.size() && static_cast<int>(i) < maxKeyframes; ++i) {
    out.push_back(scored[i].second);
  }
  return out;
}

double ReuseKeyframeSelector::memoryBytes() const
{
  double bytes = hashBucketsHeapBytes(m_samples) +
                 static_cast<double>(m_samples.size()) * hashNodeHeapBytes<decltype(m_samples)>();
  for (const auto &entry : m_samples) {
    bytes += vectorHeapBytes(entry.second.points);
  }
  return bytes;
}

std::vector<int> selectReuseKeyframes(const GlobalMap &map, const std::vector<int> &windowIds,
                                      const ReuseTarget &target, int maxKeyframes)
{
  ReuseKeyframeSelector selector;
  return selector.select(map, windowIds, target, maxKeyframes);
}

bool transferIdepth(const SE3d &targetMhost, const PinholeIntrinsics &K, double u, double v, double idepth, double var,
                    double &targetU, double &targetV, double &targetIdepth, double &targetVar)
{
  if (!(idepth > 0.)) {
    return false;
  }
  // X_target = R ray / rho + t, so rho' = 1 / z' = rho / (r_z + t_z rho) and d rho' / d rho = r_z / (r_z + t_z rho)^2.
  const Eigen::Vector3d ray((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.);
  const Eigen::Vector3d r = targetMhost.rotationMatrix() * ray;
  const Eigen::Vector3d t = targetMhost.translation();
  const double denom = r.z() + t.z() * idepth;
  if (!(denom > 0.)) {
    return false;
  }
  const Eigen::Vector3d q = r + t * idepth; // proportional to X_target
  targetU = K.fx * q.x() / q.z() + K.cx;
  targetV = K.fy * q.y() / q.z() + K.cy;
  targetIdepth = idepth / denom;
  const double d = r.z() / (denom * denom);
  targetVar = var * d * d;
  return std::isfinite(targetIdepth) && std::isfinite(targetVar);
}

double fuseInverseVariance(double a, double varA, double b, double varB, double &var)
{
  const double wa = 1. / varA, wb = 1. / varB;
  var = 1. / (wa + wb);
  return (wa * a + wb * b) * var;
}

std::vector<ReuseMatch> matchGlobalPoints(const GlobalMap &map, const std::vector<int> &keyframes,
                                          const ReuseTarget &target, const OrbMatcherOptions &options)
{
  std::vector<ProjectedPoint> projected;
  std::vector<ReuseMatch> info; // same order as projected
  for (int id : keyframes) {
    const GlobalKeyframe *kf = map.find(id);
    if (!kf) {
      continue;
    }
    const SE3d targetMhost = target.cMw * kf->cMw.inverse();
    for (size_t i = 0; i < kf->points.size(); ++i) {
      const GlobalPoint &p = kf->points[i];
      if (p.state != GlobalPointState::stored || !p.hasOrb || (target.cornersOnly && !p.isCorner)) {
        continue;
      }
      ReuseMatch m;
      double u, v;
      if (!transferIdepth(targetMhost, target.K, p.u, p.v, p.idepth, p.idepthVar, u, v, m.idepth, m.idepthVar) ||
          u < kBorderPx || v < kBorderPx || u >= target.width - kBorderPx || v >= target.height - kBorderPx) {
        continue;
      }
      m.keyframeId = id;
      m.pointIndex = i;
      ProjectedPoint pp;
      pp.u = static_cast<float>(u);
      pp.v = static_cast<float>(v);
      pp.angleDeg = p.orbAngleDeg;
      pp.descriptor = p.orb;
      projected.push_back(pp);
      info.push_back(m);
    }
  }
  std::vector<ReuseMatch> out;
  if (projected.empty() || target.keypoints.empty()) {
    return out;
  }
  const OrbMatcher matcher(target.keypoints, target.width, target.height, options);
  for (const OrbMatch &match : matcher.matchProjected(projected)) {
    ReuseMatch m = info[static_cast<size_t>(match.point)];
    m.keypoint = match.keypoint;
    m.distance = match.distance;
    out.push_back(m);
  }
  return out;
}
} // namespace hslam
