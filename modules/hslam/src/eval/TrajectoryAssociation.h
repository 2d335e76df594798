// Association of estimate timestamps with ground-truth timestamps (TUM RGB-D benchmark's associate.py rule).
#ifndef HSLAM_EVAL_TRAJECTORY_ASSOCIATION_H
#define HSLAM_EVAL_TRAJECTORY_ASSOCIATION_H

#include <visp3/core/vpConfig.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace hslam
{
/*!
  One-to-one association of estimate stamps with ground-truth stamps, each pair within \e maxDt seconds.

  Rule (as the TUM benchmark's associate.py): among all pairs with |t_est - t_gt| <= maxDt, take pairs in order of
  increasing |dt|, skipping pairs whose estimate or ground-truth stamp is already used. So every estimate stamp
  gets its nearest ground-truth stamp unless a closer estimate claimed it first.
  Cost: both lists are sorted once, candidate pairs come from a sliding window (no O(n m) scan), then one sort of
  the candidates: O((n + m) log(n + m) + c log c) with c the candidate count (n times the ground-truth rate x 2 maxDt).

  \return (estimate index, ground-truth index) pairs in the callers' indexing, sorted by estimate time.
  Input lists need not be sorted.
*/
VISP_EXPORT std::vector<std::pair<size_t, size_t>> associateTimestamps(const std::vector<double> &estimateStamps,
                                                                       const std::vector<double> &groundTruthStamps,
                                                                       double maxDt);
} // namespace hslam

#endif
