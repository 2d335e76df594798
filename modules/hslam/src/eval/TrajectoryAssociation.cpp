#include "eval/TrajectoryAssociation.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace hslam
{
namespace
{
std::vector<size_t> sortedOrder(const std::vector<double> &stamps)
{
  std::vector<size_t> order(stamps.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&stamps](size_t a, size_t b) { return stamps[a] < stamps[b]; });
  return order;
}

struct Candidate {
  double dt;       // |t_est - t_gt|, seconds
  size_t estimate; // caller's index
  size_t groundTruth;
};
} // namespace

std::vector<std::pair<size_t, size_t>> associateTimestamps(const std::vector<double> &estimateStamps,
                                                           const std::vector<double> &groundTruthStamps, double maxDt)
{
  const std::vector<size_t> estOrder = sortedOrder(estimateStamps);
  const std::vector<size_t> gtOrder = sortedOrder(groundTruthStamps);

  // Sliding window: the first ground-truth stamp >= t_est - maxDt only moves forward as t_est grows.
  std::vector<Candidate> candidates;
  size_t windowBegin = 0;
  for (size_t e : estOrder) {
    const double te = estimateStamps[e];
    while (windowBegin < gtOrder.size() && groundTruthStamps[gtOrder[windowBegin]] < te - maxDt) {
      ++windowBegin;
    }
    for (size_t k = windowBegin; k < gtOrder.size(); ++k) {
      const double dt = groundTruthStamps[gtOrder[k]] - te;
      if (dt > maxDt) {
        break;
      }
      candidates.push_back({std::abs(dt), e, gtOrder[k]});
    }
  }

  // Ties broken by index so the result does not depend on the sort implementation.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate &a, const Candidate &b) {
    return std::tie(a.dt, a.estimate, a.groundTruth) < std::tie(b.dt, b.estimate, b.groundTruth);
  });
  std::vector<char> estUsed(estimateStamps.size(), 0);
  std::vector<char> gtUsed(groundTruthStamps.size(), 0);
  std::vector<std::pair<size_t, size_t>> matches;
  for (const Candidate &c : candidates) {
    if (!estUsed[c.estimate] && !gtUsed[c.groundTruth]) {
      estUsed[c.estimate] = 1;
      gtUsed[c.groundTruth] = 1;
      matches.emplace_back(c.estimate, c.groundTruth);
    }
  }
  std::sort(matches.begin(), matches.end(), [&estimateStamps](const auto &a, const auto &b) {
    return estimateStamps[a.first] < estimateStamps[b.first] ||
           (estimateStamps[a.first] == estimateStamps[b.first] && a.first < b.first);
  });
  return matches;
}
} // namespace hslam
