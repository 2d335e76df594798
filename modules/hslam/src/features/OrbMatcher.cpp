/*
 * H-SLAM for ViSP.
 */
#include "features/OrbMatcher.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace hslam
{
OrbMatcher::OrbMatcher(const std::vector<FrameKeypoint> &keypoints, int width, int height,
                       const OrbMatcherOptions &options)
    : m_keypoints(keypoints), m_options(options)
{
  if (width <= 0 || height <= 0 || options.cellSizePx <= 0 || options.histogramBins <= 0 || !(options.ratio > 0.f)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "OrbMatcher: image size, cell size, histogram bins and ratio must be positive");
  }
  m_cols = (width + options.cellSizePx - 1) / options.cellSizePx;
  m_rows = (height + options.cellSizePx - 1) / options.cellSizePx;
  m_cells.assign(static_cast<std::size_t>(m_cols * m_rows), {});
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const int cx = static_cast<int>(std::floor(keypoints[i].u / options.cellSizePx));
    const int cy = static_cast<int>(std::floor(keypoints[i].v / options.cellSizePx));
    if (cx >= 0 && cy >= 0 && cx < m_cols && cy < m_rows) {
      m_cells[static_cast<std::size_t>(cy * m_cols + cx)].push_back(static_cast<int>(i));
    }
  }
}

void OrbMatcher::keypointsNear(float u, float v, float radius, std::vector<int> &out) const
{
  out.clear();
  const int size = m_options.cellSizePx;
  const int x0 = std::max(0, static_cast<int>(std::floor((u - radius) / size)));
  const int x1 = std::min(m_cols - 1, static_cast<int>(std::floor((u + radius) / size)));
  const int y0 = std::max(0, static_cast<int>(std::floor((v - radius) / size)));
  const int y1 = std::min(m_rows - 1, static_cast<int>(std::floor((v + radius) / size)));
  const float r2 = radius * radius;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      for (int index : m_cells[static_cast<std::size_t>(y * m_cols + x)]) {
        const float du = m_keypoints[static_cast<std::size_t>(index)].u - u;
        const float dv = m_keypoints[static_cast<std::size_t>(index)].v - v;
        if (du * du + dv * dv <= r2) {
          out.push_back(index);
        }
      }
    }
  }
}

std::vector<OrbMatch> OrbMatcher::matchProjected(const std::vector<ProjectedPoint> &points) const
{
  return matchProjected(points, m_options.radiusPx);
}

std::vector<OrbMatch> OrbMatcher::matchProjected(const std::vector<ProjectedPoint> &points, float radiusPx) const
{
  // Best point per keypoint (a keypoint claimed twice keeps the closer descriptor).
  std::vector<OrbMatch> byKeypoint(m_keypoints.size());
  std::vector<int> near;
  for (std::size_t p = 0; p < points.size(); ++p) {
    if (!std::isfinite(points[p].u) || !std::isfinite(points[p].v)) {
      continue;
    }
    keypointsNear(points[p].u, points[p].v, radiusPx, near);
    int best = 257, second = 257, bestIndex = -1;
    for (int k : near) {
      const int d = hammingDistance(points[p].descriptor, m_keypoints[static_cast<std::size_t>(k)].descriptor);
      if (d < best) {
        second = best;
        best = d;
        bestIndex = k;
      } else if (d < second) {
        second = d;
      }
    }
    if (bestIndex < 0 || best > m_options.maxDistance ||
        (second <= 256 && static_cast<float>(best) >= m_options.ratio * static_cast<float>(second))) {
      continue;
    }
    OrbMatch &slot = byKeypoint[static_cast<std::size_t>(bestIndex)];
    if (slot.point < 0 || best < slot.distance) {
      slot = {static_cast<int>(p), bestIndex, best};
    }
  }
  std::vector<OrbMatch> matches;
  for (const OrbMatch &m : byKeypoint) {
    if (m.point >= 0) {
      matches.push_back(m);
    }
  }

  if (m_options.checkOrientation && !matches.empty()) {
    const int bins = m_options.histogramBins;
    std::vector<int> binOf(matches.size());
    std::vector<int> counts(static_cast<std::size_t>(bins), 0);
    for (std::size_t i = 0; i < matches.size(); ++i) {
      float rot = m_keypoints[static_cast<std::size_t>(matches[i].keypoint)].angleDeg -
                  points[static_cast<std::size_t>(matches[i].point)].angleDeg;
      rot = std::fmod(rot, 360.f);
      if (rot < 0.f) {
        rot += 360.f;
      }
      binOf[i] = std::min(bins - 1, static_cast<int>(rot * bins / 360.f));
      ++counts[static_cast<std::size_t>(binOf[i])];
    }
    // The three fullest bins (ORB-SLAM2 ComputeThreeMaxima: a bin under 10 % of the fullest does not count).
    std::vector<int> order(static_cast<std::size_t>(bins));
    for (int b = 0; b < bins; ++b) {
      order[static_cast<std::size_t>(b)] = b;
    }
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return counts[static_cast<std::size_t>(a)] > counts[static_cast<std::size_t>(b)];
    });
    std::vector<bool> keep(static_cast<std::size_t>(bins), false);
    const int top = counts[static_cast<std::size_t>(order[0])];
    for (int i = 0; i < 3 && i < bins; ++i) {
      const int c = counts[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])];
      if (c > 0 && (i == 0 || 10 * c >= top)) {
        keep[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])] = true;
      }
    }
    std::vector<OrbMatch> consistent;
    for (std::size_t i = 0; i < matches.size(); ++i) {
      if (keep[static_cast<std::size_t>(binOf[i])]) {
        consistent.push_back(matches[i]);
      }
    }
    matches.swap(consistent);
  }
  std::sort(matches.begin(), matches.end(), [](const OrbMatch &a, const OrbMatch &b) { return a.point < b.point; });
  return matches;
}
} // namespace hslam
