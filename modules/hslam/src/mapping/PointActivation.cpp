/*
 * H-SLAM for ViSP.
 */
#include "mapping/PointActivation.h"

#include "mapping/ImmaturePointTracer.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace hslam
{
namespace
{
//! DSO's minimum-distance adaptation (currentMinActDist): one row = (fraction of the desired count, change of the
//! minimum distance in pixels at the map's level).
struct DensityStep {
  double fraction;
  float change;
};
//! Too few points: the first row whose fraction is not reached lowers the distance ...
constexpr DensityStep kShortageSteps[] = {{0.8, 0.5f}, {0.9, 0.2f}, {1.0, 0.1f}};
//! ... and below this fraction the distance drops by an extra step.
constexpr double kSevereShortage = 0.66;
constexpr float kSevereShortageChange = 0.8f;
//! Too many points: every row whose fraction is exceeded raises the distance (the changes add up).
constexpr DensityStep kExcessSteps[] = {{1.5, 0.8f}, {1.3, 0.5f}, {1.15, 0.2f}, {1.0, 0.1f}};
//! Range of the minimum distance, pixels at the distance map's level (DSO).
constexpr float kMinDistanceLower = 0.f;
constexpr float kMinDistanceUpper = 4.f;
//! Rounding offset of a projection to the distance map's pixel grid (nearest pixel, DSO: int(x + 0.5)).
constexpr float kRoundingOffset = 0.5f;
//! Denominator of the variance of a uniform distribution: width^2 / 12.
constexpr float kUniformVarianceDenominator = 12.f;

inline bool insideDistanceMap(int u, int v, int width, int height)
{
  // DSO excludes the first row and column as well as everything outside.
  return u > 0 && v > 0 && u < width && v < height;
}

//! Level-0 -> distance-map-level projection matrices for points hosted in \e host, seen in \e newest.
void pairProjection(const Frame &host, const Frame &newest, const PinholeIntrinsics &Kmap, const PinholeIntrinsics &K0,
                    Eigen::Matrix3f &KRKi, Eigen::Vector3f &Kt)
{
  Eigen::Matrix3d Km = Eigen::Matrix3d::Identity();
  Km(0, 0) = Kmap.fx;
  Km(1, 1) = Kmap.fy;
  Km(0, 2) = Kmap.cx;
  Km(1, 2) = Kmap.cy;
  Eigen::Matrix3d Ki = Eigen::Matrix3d::Identity();
  Ki(0, 0) = 1. / K0.fx;
  Ki(1, 1) = 1. / K0.fy;
  Ki(0, 2) = -K0.cx / K0.fx;
  Ki(1, 2) = -K0.cy / K0.fy;
  const SE3d newestMhost = newest.cMw * host.cMw.inverse();
  KRKi = (Km * newestMhost.rotationMatrix() * Ki).cast<float>();
  Kt = (Km * newestMhost.translation()).cast<float>();
}

void requireFrame(const Keyframe &kf, const char *what)
{
  if (!kf.frame || kf.frame->pyramid.numLevels() < 1) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ": " + what + ": keyframe without frame or image pyramid");
  }
}
} // namespace

PointActivation::PointActivation(const vpHSlamParameters::Mapper &mapper)
    : m_maxTraceInterval(static_cast<float>(mapper.maxTraceInterval)),
      m_minTraceQuality(static_cast<float>(mapper.minTraceQuality)),
      m_minDistance(static_cast<float>(mapper.activationMinDistance))
{
}

void PointActivation::resize(int width, int height)
{
  if (width <= 0 || height <= 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                  ": distance map size " + std::to_string(width) + "x" +
                                                                  std::to_string(height) + " must be positive");
  }
  m_width = width;
  m_height = height;
  const size_t size = static_cast<size_t>(width) * static_cast<size_t>(height);
  m_distance.assign(size, kFarDistance);
  // A pixel enters a front at most once per step, so a front never holds more than every pixel.
  if (m_front.size() < size) {
    m_front.resize(size);
    m_next.resize(size);
  }
}

void PointActivation::buildDistanceMap(int width, int height, const std::vector<std::pair<int, int>> &seeds)
{
  resize(width, height);
  int count = 0;
  for (const std::pair<int, int> &seed : seeds) {
    if (!insideDistanceMap(seed.first, seed.second, m_width, m_height)) {
      continue;
    }
    float &d = m_distance[static_cast<size_t>(seed.second * m_width + seed.first)];
    if (d == 0.f) {
      continue; // duplicate seed
    }
    d = 0.f;
    m_front[static_cast<size_t>(count++)] = seed;
  }
  growFromSeeds(count);
}

void PointActivation::buildDistanceMap(const std::vector<KeyframePtr> &window, const Keyframe &newest)
{
  requireFrame(newest, "PointActivation::buildDistanceMap");
  const PyramidLevel &level0 = newest.frame->pyramid.level(0);
  // DSO: the map lives at level 1 (w >> 1, h >> 1) with the halved intrinsics of the pixel-centre convention.
  PinholeIntrinsics Kmap = level0.K;
  for (int l = 0; l < kDistanceMapLevel; ++l) {
    Kmap = Kmap.halved();
  }
  resize(level0.width >> kDistanceMapLevel, level0.height >> kDistanceMapLevel);

  int count = 0;
  for (const KeyframePtr &host : window) {
    if (!host || host.get() == &newest || !host->frame) {
      continue;
    }
    Eigen::Matrix3f KRKi;
    Eigen::Vector3f Kt;
    pairProjection(*host->frame, *newest.frame, Kmap, level0.K, KRKi, Kt);
    for (const MapPoint &p : host->points) {
      if (p.status != PointStatus::active) {
        continue;
      }
      const Eigen::Vector3f ptp = KRKi * Eigen::Vector3f(p.u, p.v, 1.f) + Kt * static_cast<float>(p.idepth);
      if (!(ptp.z() > 0.f)) {
        continue;
      }
      const int u = static_cast<int>(std::floor(ptp.x() / ptp.z() + kRoundingOffset));
      const int v = static_cast<int>(std::floor(ptp.y() / ptp.z() + kRoundingOffset));
      if (!insideDistanceMap(u, v, m_width, m_height)) {
        continue;
      }
      float &d = m_distance[static_cast<size_t>(v * m_width + u)];
      if (d == 0.f) {
        continue;
      }
      d = 0.f;
      m_front[static_cast<size_t>(count++)] = {u, v};
    }
  }
  growFromSeeds(count);
}

void PointActivation::growFromSeeds(int seedCount)
{
  // Layered breadth-first search; odd steps use the 8-neighbourhood, even steps the 4-neighbourhood, so the
  // distance grows like an octagon, close to Euclidean (DSO growDistBFS). Border pixels are not expanded.
  static constexpr int kOffsets[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
  static constexpr int kFourNeighbours = 4;
  static constexpr int kEightNeighbours = 8;
  int frontSize = seedCount;
  for (int k = 1; k < kMaxSearchSteps && frontSize > 0; ++k) {
    const float distance = static_cast<float>(k);
    const int neighbours = (k % 2 == 1) ? kEightNeighbours : kFourNeighbours;
    int nextSize = 0;
    for (int i = 0; i < frontSize; ++i) {
      const int x = m_front[static_cast<size_t>(i)].first;
      const int y = m_front[static_cast<size_t>(i)].second;
      if (x == 0 || y == 0 || x == m_width - 1 || y == m_height - 1) {
        continue;
      }
      for (int n = 0; n < neighbours; ++n) {
        const int nx = x + kOffsets[n][0];
        const int ny = y + kOffsets[n][1];
        float &d = m_distance[static_cast<size_t>(ny * m_width + nx)];
        if (d > distance) {
          d = distance;
          m_next[static_cast<size_t>(nextSize++)] = {nx, ny};
        }
      }
    }
    m_front.swap(m_next);
    frontSize = nextSize;
  }
}

bool PointActivation::canActivate(float u, float v, int selectionLevel) const
{
  if (m_width == 0 || !std::isfinite(u) || !std::isfinite(v)) {
    return false;
  }
  const int iu = static_cast<int>(std::floor(u + kRoundingOffset));
  const int iv = static_cast<int>(std::floor(v + kRoundingOffset));
  if (!insideDistanceMap(iu, iv, m_width, m_height)) {
    return false;
  }
  const float jitter = u - std::floor(u);
  const float levelFactor = static_cast<float>(1 << std::max(0, selectionLevel));
  return distanceAt(iu, iv) + jitter >= m_minDistance * levelFactor;
}

void PointActivation::addActivated(int u, int v)
{
  if (!insideDistanceMap(u, v, m_width, m_height)) {
    return;
  }
  m_distance[static_cast<size_t>(v * m_width + u)] = 0.f;
  m_front[0] = {u, v};
  growFromSeeds(1);
}

void PointActivation::adaptMinDistance(int activeCount, int desiredCount)
{
  const double count = static_cast<double>(activeCount);
  const double desired = static_cast<double>(desiredCount);
  // DSO: a severe shortage lowers the distance by a large step on top of the graded one.
  if (count < desired * kSevereShortage) {
    m_minDistance -= kSevereShortageChange;
  }
  for (const DensityStep &step : kShortageSteps) {
    if (count < desired * step.fraction) {
      m_minDistance -= step.change;
      break;
    }
  }
  for (const DensityStep &step : kExcessSteps) {
    if (count > desired * step.fraction) {
      m_minDistance += step.change;
    }
  }
  m_minDistance = std::max(kMinDistanceLower, std::min(kMinDistanceUpper, m_minDistance));
}

bool PointActivation::isReady(const ImmaturePoint &pt, float pixelInterval) const
{
  const bool statusAllows = pt.lastStatus == TraceStatus::good || pt.lastStatus == TraceStatus::skipped ||
                            pt.lastStatus == TraceStatus::badCondition || pt.lastStatus == TraceStatus::outOfBounds;
  return statusAllows && pixelInterval < m_maxTraceInterval && pt.quality > m_minTraceQuality &&
         (pt.idepthMax + pt.idepthMin) > 0.f;
}

ActivationPlan PointActivation::selectPoints(const std::vector<KeyframePtr> &window, const Keyframe &newest)
{
  requireFrame(newest, "PointActivation::selectPoints");
  ActivationPlan plan;
  const PyramidLevel &level0 = newest.frame->pyramid.level(0);
  PinholeIntrinsics Kmap = level0.K;
  for (int l = 0; l < kDistanceMapLevel; ++l) {
    Kmap = Kmap.halved();
  }
  const float scaleToLevel0 = static_cast<float>(1 << kDistanceMapLevel);
  for (size_t w = 0; w < window.size(); ++w) {
    const KeyframePtr &host = window[w];
    if (!host || host.get() == &newest || !host->frame) {
      continue;
    }
    Eigen::Matrix3f KRKi;
    Eigen::Vector3f Kt;
    pairProjection(*host->frame, *newest.frame, Kmap, level0.K, KRKi, Kt);
    const SE3d newestMhost = newest.frame->cMw * host->frame->cMw.inverse();
    for (size_t i = 0; i < host->immature.size(); ++i) {
      const ImmaturePoint &pt = host->immature[i];
      const ImmaturePointRef ref{static_cast<int>(w), static_cast<int>(i)};
      // Never traced successfully, or an outlier at the last trace: drop (DSO).
      if (!std::isfinite(pt.idepthMax) || pt.lastStatus == TraceStatus::outlier) {
        plan.drop.push_back(ref);
        continue;
      }
      const float pixelInterval = ImmaturePointTracer::projectedIntervalLength(pt, newestMhost, level0.K);
      if (!isReady(pt, pixelInterval)) {
        if (pt.lastStatus == TraceStatus::outOfBounds) {
          plan.drop.push_back(ref); // will never be traced again
        }
        continue;
      }
      const float idepth = initialIdepth(pt);
      const Eigen::Vector3f ptp = KRKi * Eigen::Vector3f(pt.u, pt.v, 1.f) + Kt * idepth;
      const float um = ptp.x() / ptp.z();
      const float vm = ptp.y() / ptp.z();
      const int iu = static_cast<int>(std::floor(um + kRoundingOffset));
      const int iv = static_cast<int>(std::floor(vm + kRoundingOffset));
      if (!(ptp.z() > 0.f) || !insideDistanceMap(iu, iv, m_width, m_height)) {
        plan.drop.push_back(ref); // not visible in the newest keyframe
        continue;
      }
      if (pt.descriptorOnly || !canActivate(um, vm, pt.selectionLevel)) {
        continue;
      }
      addActivated(iu, iv);
      ActivationCandidate candidate;
      candidate.ref = ref;
      candidate.hostKeyframeId = pt.hostKeyframeId;
      candidate.idepth = idepth;
      candidate.idepthMin = pt.idepthMin;
      candidate.idepthMax = pt.idepthMax;
      // Back to level 0 with the pixel-centre convention: x0 = (x_l + 0.5) 2^l - 0.5.
      candidate.uNewest = (um + kRoundingOffset) * scaleToLevel0 - kRoundingOffset;
      candidate.vNewest = (vm + kRoundingOffset) * scaleToLevel0 - kRoundingOffset;
      plan.activate.push_back(candidate);
    }
  }
  return plan;
}

MapPoint PointActivation::makeMapPoint(const ImmaturePoint &pt)
{
  MapPoint p;
  p.hostKeyframeId = pt.hostKeyframeId;
  p.u = pt.u;
  p.v = pt.v;
  p.idepth = static_cast<double>(initialIdepth(pt));
  const float width = pt.idepthMax - pt.idepthMin;
  p.idepthVar = static_cast<double>(width * width / kUniformVarianceDenominator);
  p.status = PointStatus::active;
  p.isCorner = pt.isCorner;
  p.patch = pt.patch;
  p.patchWeight = pt.patchWeight;
  p.orb = pt.orb;
  p.orbAngleDeg = pt.orbAngleDeg;
  p.hasOrb = pt.hasOrb;
  return p;
}

void PointActivation::eraseImmaturePoints(const std::vector<KeyframePtr> &window,
                                          const std::vector<ImmaturePointRef> &refs)
{
  // Flag, then compact each host's list once (stable: the remaining points keep their order).
  std::vector<std::vector<bool>> erase(window.size());
  for (const ImmaturePointRef &ref : refs) {
    if (ref.windowIndex < 0 || ref.windowIndex >= static_cast<int>(window.size()) ||
        !window[static_cast<size_t>(ref.windowIndex)]) {
      continue;
    }
    const size_t count = window[static_cast<size_t>(ref.windowIndex)]->immature.size();
    std::vector<bool> &flags = erase[static_cast<size_t>(ref.windowIndex)];
    flags.resize(count, false);
    if (ref.pointIndex >= 0 && static_cast<size_t>(ref.pointIndex) < count) {
      flags[static_cast<size_t>(ref.pointIndex)] = true;
    }
  }
  for (size_t w = 0; w < window.size(); ++w) {
    if (erase[w].empty()) {
      continue;
    }
    std::vector<ImmaturePoint> &list = window[w]->immature;
    size_t kept = 0;
    for (size_t i = 0; i < list.size(); ++i) {
      if (!erase[w][i]) {
        if (kept != i) {
          list[kept] = list[i];
        }
        ++kept;
      }
    }
    list.resize(kept);
  }
}
} // namespace hslam
