/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopVerification.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>

namespace hslam
{
namespace
{
//! Scale between ORB pyramid levels (OrbExtractorOptions::scaleFactor): a keypoint's pixel noise grows with it.
constexpr double kLevelScale = 1.2;

//! Every point of a side in the camera of its first keyframe, keyframe by keyframe (those behind that camera are left
//! out): a side's points are the concatenation of these slices.
std::vector<std::vector<LoopPoint>> sidePoints(const std::vector<LoopSideKeyframe> &side, const PinholeIntrinsics &K)
{
  std::vector<std::vector<LoopPoint>> slices;
  for (const LoopSideKeyframe &kf : side) {
    const LoopKeyframe &f = *kf.features;
    std::vector<LoopPoint> &points = slices.emplace_back();
    for (size_t i = 0; i < f.X.size(); ++i) {
      LoopPoint p;
      p.X = kf.sideMkeyframe * Eigen::Vector3d(f.X[i].cast<double>());
      if (!(p.X.z() > 0.)) {
        continue;
      }
      p.uv = K.project(p.X);
      p.orb = f.orb[i];
      p.keyframeId = f.id;
      p.pointIndex = i;
      p.octave = i < f.octave.size() ? f.octave[i] : 0;
      points.push_back(p);
    }
  }
  return slices;
}

//! All the points of a side's slices, one after the other.
std::vector<LoopPoint> concatenate(const std::vector<std::vector<LoopPoint>> &slices)
{
  std::vector<LoopPoint> all;
  for (const std::vector<LoopPoint> &slice : slices) {
    all.insert(all.end(), slice.begin(), slice.end());
  }
  return all;
}

//! Where each slice starts in the concatenated side, and (last entry) the side's size.
std::vector<size_t> sliceBegins(const std::vector<std::vector<LoopPoint>> &slices)
{
  std::vector<size_t> begins = {0};
  for (const std::vector<LoopPoint> &slice : slices) {
    begins.push_back(begins.back() + slice.size());
  }
  return begins;
}

//! Step 1: keyframe by keyframe matches, each point at most once (closest pair first). Pairs of indices into the
//! concatenated sides.
std::vector<std::pair<int, int>> matchSides(const std::vector<std::vector<LoopPoint>> &a,
                                            const std::vector<std::vector<LoopPoint>> &b,
                                            const LoopVerificationOptions &o)
{
  struct Pair {
    int distance, ia, ib;
  };
  const std::vector<size_t> beginA = sliceBegins(a), beginB = sliceBegins(b);
  std::vector<Pair> pairs;
  for (size_t ka = 0; ka < a.size(); ++ka) {
    for (size_t kb = 0; kb < b.size(); ++kb) {
      for (const auto &m : matchLoopPoints(a[ka], b[kb], o.maxDistance, o.ratio)) {
        const LoopPoint &pa = a[ka][static_cast<size_t>(m.first)], &pb = b[kb][static_cast<size_t>(m.second)];
        pairs.push_back({hammingDistance(pa.orb, pb.orb), static_cast<int>(beginA[ka]) + m.first,
                         static_cast<int>(beginB[kb]) + m.second});
      }
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair &x, const Pair &y) { return x.distance < y.distance; });
  std::vector<bool> usedA(beginA.back(), false), usedB(beginB.back(), false);
  std::vector<std::pair<int, int>> out;
  for (const Pair &p : pairs) {
    if (!usedA[static_cast<size_t>(p.ia)] && !usedB[static_cast<size_t>(p.ib)]) {
      usedA[static_cast<size_t>(p.ia)] = usedB[static_cast<size_t>(p.ib)] = true;
      out.emplace_back(p.ia, p.ib);
    }
  }
  return out;
}

/*!
  Side A's points by square cell of the largest search radius, so that a projection's candidates are those of the
  3 x 3 cells around it (guided matching compared every B point with every A point: most of a verification's
  time). The cells are sorted keys, not an array (OrbMatcher's grid covers one image): a side's points and
  projections can lie anywhere, and a point just in front of a camera projects arbitrarily far.
*/
class PixelGrid
{
public:
  PixelGrid(const std::vector<LoopPoint> &points, double cellPx) : m_cell(cellPx)
  {
    for (size_t i = 0; i < points.size(); ++i) {
      if (points[i].uv.allFinite()) {
        m_entries.push_back({cellOf(points[i].uv.y()), cellOf(points[i].uv.x()), static_cast<int>(i)});
      }
    }
    std::sort(m_entries.begin(), m_entries.end());
  }
  //! Calls \e f(i) for the points of the cells around \e uv (a superset of those within one cell of it).
  template <class F> void forEachNear(const Eigen::Vector2d &uv, F f) const
  {
    if (!uv.allFinite()) {
      return;
    }
    const std::int64_t row = cellOf(uv.y()), col = cellOf(uv.x());
    for (std::int64_t r = row - 1; r <= row + 1; ++r) {
      auto it = std::lower_bound(m_entries.begin(), m_entries.end(), Entry{r, col - 1, -1});
      for (; it != m_entries.end() && it->row == r && it->col <= col + 1; ++it) {
        f(it->index);
      }
    }
  }

private:
  struct Entry {
    std::int64_t row, col;
    int index;
    bool operator<(const Entry &o) const { return std::tie(row, col, index) < std::tie(o.row, o.col, o.index); }
  };
  std::int64_t cellOf(double px) const
  {
    constexpr double kFar = 1e12; // cells beyond this are one cell: nothing projects there usefully
    return static_cast<std::int64_t>(std::floor(std::clamp(px / m_cell, -kFar, kFar)));
  }
  double m_cell;
  std::vector<Entry> m_entries;
};

//! Step 3: B points mapped by S21 into A's camera, each paired with the closest unmatched A point in descriptor
//! within the radius of its projection (and in front; the lowest index among equals). Appends to \e pairs;
//! returns how many were added.
int guidedMatches(const std::vector<LoopPoint> &a, const std::vector<LoopPoint> &b, const Sim3d &S21,
                  const PinholeIntrinsics &K, const LoopVerificationOptions &o, std::vector<std::pair<int, int>> &pairs)
{
  std::vector<bool> usedA(a.size(), false), usedB(b.size(), false);
  for (const auto &p : pairs) {
    usedA[static_cast<size_t>(p.first)] = usedB[static_cast<size_t>(p.second)] = true;
  }
  std::vector<double> radius2(a.size());
  double maxRadius = o.guidedRadiusPx;
  for (size_t i = 0; i < a.size(); ++i) {
    const double r = o.guidedRadiusPx * std::pow(kLevelScale, a[i].octave);
    radius2[i] = r * r;
    maxRadius = std::max(maxRadius, r);
  }
  const PixelGrid grid(a, std::max(maxRadius, 1.));
  int added = 0;
  for (size_t j = 0; j < b.size(); ++j) {
    if (usedB[j]) {
      continue;
    }
    const Eigen::Vector3d X2 = S21 * b[j].X;
    if (!(X2.z() > 0.)) {
      continue;
    }
    const Eigen::Vector2d uv = K.project(X2);
    int best = o.maxDistance + 1, bestIndex = -1;
    grid.forEachNear(uv, [&](int i) {
      const size_t k = static_cast<size_t>(i);
      if (usedA[k] || (a[k].uv - uv).squaredNorm() > radius2[k]) {
        return;
      }
      const int d = hammingDistance(a[k].orb, b[j].orb);
      if (d < best || (d == best && i < bestIndex)) {
        best = d;
        bestIndex = i;
      }
    });
    if (bestIndex >= 0) {
      usedA[static_cast<size_t>(bestIndex)] = usedB[j] = true;
      pairs.emplace_back(bestIndex, static_cast<int>(j));
      ++added;
    }
  }
  return added;
}

std::vector<Sim3Correspondence> correspondences(const std::vector<LoopPoint> &a, const std::vector<LoopPoint> &b,
                                                const std::vector<std::pair<int, int>> &pairs)
{
  std::vector<Sim3Correspondence> out;
  out.reserve(pairs.size());
  for (const auto &p : pairs) {
    const LoopPoint &pa = a[static_cast<size_t>(p.first)], &pb = b[static_cast<size_t>(p.second)];
    out.push_back({pb.X, pa.X, pb.uv, pa.uv}); // 1: candidate side, 2: query side
  }
  return out;
}
} // namespace

LoopVerification verifyLoopSides(const std::vector<LoopSideKeyframe> &query,
                                 const std::vector<LoopSideKeyframe> &candidate, const PinholeIntrinsics &K,
                                 const LoopVerificationOptions &options)
{
  LoopVerification result;
  if (query.empty() || candidate.empty()) {
    return result;
  }
  const std::vector<std::vector<LoopPoint>> sliceA = sidePoints(query, K), sliceB = sidePoints(candidate, K);
  const std::vector<LoopPoint> a = concatenate(sliceA), b = concatenate(sliceB);
  std::vector<std::pair<int, int>> pairs = matchSides(sliceA, sliceB, options);
  result.matches = static_cast<int>(pairs.size());
  if (result.matches < options.minMatches) {
    return result;
  }
  // Step 2: a hypothesis needs half the final inliers; guided matching and the final count decide.
  Sim3RansacOptions ransac;
  ransac.minInliers = std::max(6, options.minInliers / 2);
  ransac.maxReprojectionPx = options.thresholdPx;
  ransac.seed = options.seed;
  const Sim3Estimate hypothesis = estimateSim3Ransac(correspondences(a, b, pairs), K, K, ransac);
  result.estimate = hypothesis;
  if (!hypothesis.success) {
    return result;
  }
  // Step 3 keeps the hypothesis' inliers only: its outliers would claim the places of right matches.
  std::vector<std::pair<int, int>> kept;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (hypothesis.inliers[k]) {
      kept.push_back(pairs[k]);
    }
  }
  result.guidedMatches = guidedMatches(a, b, hypothesis.S21, K, options, kept);
  // Step 4: the similarity of all matches (the sampler starts again on a set that is mostly right).
  ransac.minInliers = options.minInliers;
  result.estimate = estimateSim3Ransac(correspondences(a, b, kept), K, K, ransac);
  if (!result.estimate.success) {
    return result;
  }
  for (size_t k = 0; k < kept.size(); ++k) {
    if (result.estimate.inliers[k]) {
      const LoopPoint &pa = a[static_cast<size_t>(kept[k].first)], &pb = b[static_cast<size_t>(kept[k].second)];
      result.inliers.push_back({pa, pb});
      result.centralInliers +=
          pa.keyframeId == query.front().features->id && pb.keyframeId == candidate.front().features->id ? 1 : 0;
    }
  }
  // The two ends themselves must see the place: a similarity supported by their neighbours only relates other
  // keyframes through poses that are not measured here (synthetic room: 60 degrees apart, "closed" through their
  // neighbours with a 4 degree error).
  if (result.centralInliers < options.minInliers / 2) {
    result.estimate.success = false;
    result.inliers.clear();
  }
  return result;
}
} // namespace hslam
