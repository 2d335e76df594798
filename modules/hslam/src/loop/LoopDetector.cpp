/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopDetector.h"

#include <algorithm>
#include <limits>

namespace hslam
{
std::vector<int> LoopConsistency::update(const std::vector<std::pair<int, std::vector<int>>> &candidateGroups)
{
  std::vector<int> accepted;
  std::vector<std::pair<std::set<int>, int>> current;
  for (const auto &candidate : candidateGroups) {
    std::set<int> group(candidate.second.begin(), candidate.second.end());
    group.insert(candidate.first);
    int count = 0;
    for (const auto &previous : m_groups) {
      const bool shares = std::any_of(group.begin(), group.end(), [&](int id) { return previous.first.count(id); });
      if (shares) {
        count = std::max(count, previous.second + 1);
      }
    }
    if (count >= m_required - 1 && std::find(accepted.begin(), accepted.end(), candidate.first) == accepted.end()) {
      accepted.push_back(candidate.first);
    }
    current.emplace_back(std::move(group), count);
  }
  m_groups.swap(current);
  return accepted;
}

namespace
{
//! A descriptor's closest and second-closest distance in a set, and the closest one's index (-1: empty set).
struct ClosestTwo {
  int best = std::numeric_limits<int>::max(), second = std::numeric_limits<int>::max(), index = -1;
};

/*!
  For each descriptor of \e queries, its two closest in \e set (ties keep the first). kBuiltin: distances by
  hammingDistanceBuiltin() (only where inlined into closestTwoWithPopcnt()), else by hammingDistance(); the same
  numbers either way (BinaryDescriptor.h).
*/
template <bool kBuiltin>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void
closestTwoIn(const std::vector<OrbDescriptor> &set, const std::vector<OrbDescriptor> &queries,
             std::vector<ClosestTwo> &out)
{
  out.assign(queries.size(), ClosestTwo());
  for (size_t j = 0; j < queries.size(); ++j) {
    ClosestTwo &c = out[j];
    for (size_t i = 0; i < set.size(); ++i) {
      const int d = kBuiltin ? hammingDistanceBuiltin(set[i], queries[j]) : hammingDistance(set[i], queries[j]);
      if (d < c.best) {
        c.second = c.best;
        c.best = d;
        c.index = static_cast<int>(i);
      } else if (d < c.second) {
        c.second = d;
      }
    }
  }
}

HSLAM_TARGET_POPCNT void closestTwoWithPopcnt(const std::vector<OrbDescriptor> &set,
                                              const std::vector<OrbDescriptor> &queries, std::vector<ClosestTwo> &out)
{
  closestTwoIn<HSLAM_POPCNT_DISPATCH != 0>(set, queries, out);
}

void closestTwoPortable(const std::vector<OrbDescriptor> &set, const std::vector<OrbDescriptor> &queries,
                        std::vector<ClosestTwo> &out)
{
  closestTwoIn<false>(set, queries, out);
}

std::vector<OrbDescriptor> descriptorsOf(const std::vector<LoopPoint> &points)
{
  std::vector<OrbDescriptor> d(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    d[i] = points[i].orb;
  }
  return d;
}
} // namespace

std::vector<std::pair<int, int>> matchLoopPoints(const std::vector<LoopPoint> &a, const std::vector<LoopPoint> &b,
                                                 int maxDistance, double ratio)
{
  // The descriptors side by side (a LoopPoint is 96 bytes, its descriptor 32): verification matches every pair of
  // its two sides' keyframes, about a tenth of slam's time on Tsukuba there and back before.
  const std::vector<OrbDescriptor> setA = descriptorsOf(a), setB = descriptorsOf(b);
  std::vector<ClosestTwo> closest;
  if (cpuHasPopcnt()) {
    closestTwoWithPopcnt(setA, setB, closest);
  } else {
    closestTwoPortable(setA, setB, closest);
  }
  // Best b for each a, with the b's distance: an a point goes to its closest b only.
  std::vector<int> owner(a.size(), -1);
  std::vector<int> ownerDistance(a.size(), std::numeric_limits<int>::max());
  for (size_t j = 0; j < b.size(); ++j) {
    const ClosestTwo &c = closest[j];
    if (c.index < 0 || c.best > maxDistance || !(c.best < ratio * c.second)) {
      continue;
    }
    if (c.best < ownerDistance[static_cast<size_t>(c.index)]) {
      ownerDistance[static_cast<size_t>(c.index)] = c.best;
      owner[static_cast<size_t>(c.index)] = static_cast<int>(j);
    }
  }
  std::vector<std::pair<int, int>> out;
  for (size_t i = 0; i < a.size(); ++i) {
    if (owner[i] >= 0) {
      out.emplace_back(static_cast<int>(i), owner[i]);
    }
  }
  return out;
}
} // namespace hslam
