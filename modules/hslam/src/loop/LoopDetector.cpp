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

std::vector<std::pair<int, int>> matchLoopPoints(const std::vector<LoopPoint> &a, const std::vector<LoopPoint> &b,
                                                 int maxDistance, double ratio)
{
  // Best b for each a, with the b's distance: an a point goes to its closest b only.
  std::vector<int> owner(a.size(), -1);
  std::vector<int> ownerDistance(a.size(), std::numeric_limits<int>::max());
  for (size_t j = 0; j < b.size(); ++j) {
    int best = std::numeric_limits<int>::max(), second = best, bestIndex = -1;
    for (size_t i = 0; i < a.size(); ++i) {
      const int d = hammingDistance(a[i].orb, b[j].orb);
      if (d < best) {
        second = best;
        best = d;
        bestIndex = static_cast<int>(i);
      } else if (d < second) {
        second = d;
      }
    }
    if (bestIndex < 0 || best > maxDistance || !(best < ratio * second)) {
      continue;
    }
    if (best < ownerDistance[static_cast<size_t>(bestIndex)]) {
      ownerDistance[static_cast<size_t>(bestIndex)] = best;
      owner[static_cast<size_t>(bestIndex)] = static_cast<int>(j);
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
