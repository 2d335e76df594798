/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopVerification.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hslam
{
namespace
{
//! Scale between ORB pyramid levels (OrbExtractorOptions::scaleFactor): a keypoint's pixel noise grows with it.
constexpr double kLevelScale = 1.2;

//! Every point of a side in the camera of its first keyframe; those behind that camera are left out.
std::vector<LoopPoint> sidePoints(const std::vector<LoopSideKeyframe> &side, const PinholeIntrinsics &K,
                                  std::vector<size_t> &keyframeBegin, std::vector<std::uint8_t> &octave)
{
  std::vector<LoopPoint> points;
  keyframeBegin.clear();
  octave.clear();
  for (const LoopSideKeyframe &kf : side) {
    keyframeBegin.push_back(points.size());
    const LoopKeyframe &f = *kf.features;
    for (size_t i = 0; i < f.X.size(); ++i) {
      LoopPoint p;
      p.X = kf.sideMkeyframe * Eigen::Vector3d(f.X[i].cast<double>());
      if (!(p.X.z() > 0.)) {
        continue;
      }
      p.uv = Eigen::Vector2d(K.fx * p.X.x() / p.X.z() + K.cx, K.fy * p.X.y() / p.X.z() + K.cy);
      p.orb = f.orb[i];
      p.keyframeId = f.id;
      p.pointIndex = i;
      points.push_back(p);
      octave.push_back(i < f.octave.size() ? f.octave[i] : 0);
    }
  }
  keyframeBegin.push_back(points.size());
  return points;
}

//! Step 1: keyframe by keyframe matches, each point at most once (closest pair first). Pairs (index in a, in b).
std::vector<std::pair<int, int>> matchSides(const std::vector<LoopPoint> &a, const std::vector<size_t> &aBegin,
                                            const std::vector<LoopPoint> &b, const std::vector<size_t> &bBegin,
                                            const LoopVerificationOptions &o)
{
  struct Pair {
    int distance, ia, ib;
  };
  std::vector<Pair> pairs;
  for (size_t ka = 0; ka + 1 < aBegin.size(); ++ka) {
    const std::vector<LoopPoint> sa(a.begin() + static_cast<long>(aBegin[ka]),
                                    a.begin() + static_cast<long>(aBegin[ka + 1]));
    for (size_t kb = 0; kb + 1 < bBegin.size(); ++kb) {
      const std::vector<LoopPoint> sb(b.begin() + static_cast<long>(bBegin[kb]),
                                      b.begin() + static_cast<long>(bBegin[kb + 1]));
      for (const auto &m : matchLoopPoints(sa, sb, o.maxDistance, o.ratio)) {
        const int ia = static_cast<int>(aBegin[ka]) + m.first, ib = static_cast<int>(bBegin[kb]) + m.second;
        pairs.push_back({hammingDistance(a[static_cast<size_t>(ia)].orb, b[static_cast<size_t>(ib)].orb), ia, ib});
      }
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair &x, const Pair &y) { return x.distance < y.distance; });
  std::vector<bool> usedA(a.size(), false), usedB(b.size(), false);
  std::vector<std::pair<int, int>> out;
  for (const Pair &p : pairs) {
    if (!usedA[static_cast<size_t>(p.ia)] && !usedB[static_cast<size_t>(p.ib)]) {
      usedA[static_cast<size_t>(p.ia)] = usedB[static_cast<size_t>(p.ib)] = true;
      out.emplace_back(p.ia, p.ib);
    }
  }
  return out;
}

//! Step 3: B points mapped by S21 into A's camera, each paired with the closest unmatched A point in descriptor
//! within the radius of its projection (and in front). Appends to \e pairs; returns how many were added.
int guidedMatches(const std::vector<LoopPoint> &a, const std::vector<std::uint8_t> &aOctave,
                  const std::vector<LoopPoint> &b, const Sim3d &S21, const PinholeIntrinsics &K,
                  const LoopVerificationOptions &o, std::vector<std::pair<int, int>> &pairs)
{
  std::vector<bool> usedA(a.size(), false), usedB(b.size(), false);
  for (const auto &p : pairs) {
    usedA[static_cast<size_t>(p.first)] = usedB[static_cast<size_t>(p.second)] = true;
  }
  int added = 0;
  for (size_t j = 0; j < b.size(); ++j) {
    if (usedB[j]) {
      continue;
    }
    const Eigen::Vector3d X2 = S21 * b[j].X;
    if (!(X2.z() > 0.)) {
      continue;
    }
    const Eigen::Vector2d uv(K.fx * X2.x() / X2.z() + K.cx, K.fy * X2.y() / X2.z() + K.cy);
    int best = o.maxDistance + 1, bestIndex = -1;
    for (size_t i = 0; i < a.size(); ++i) {
      const double radius = o.guidedRadiusPx * std::pow(kLevelScale, aOctave[i]);
      if (usedA[i] || (a[i].uv - uv).squaredNorm() > radius * radius) {
        continue;
      }
      const int d = hammingDistance(a[i].orb, b[j].orb);
      if (d < best) {
        best = d;
        bestIndex = static_cast<int>(i);
      }
    }
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
  std::vector<size_t> aBegin, bBegin;
  std::vector<std::uint8_t> aOctave, bOctave;
  const std::vector<LoopPoint> a = sidePoints(query, K, aBegin, aOctave);
  const std::vector<LoopPoint> b = sidePoints(candidate, K, bBegin, bOctave);
  std::vector<std::pair<int, int>> pairs = matchSides(a, aBegin, b, bBegin, options);
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
  result.guidedMatches = guidedMatches(a, aOctave, b, hypothesis.S21, K, options, kept);
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
