/*
 * H-SLAM for ViSP.
 */
#include "loop/GlobalBundleJob.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
std::unique_ptr<GlobalBundleJob> makeGlobalBundleJob(const GlobalMap &map, int segment,
                                                     const std::map<int, SE3d> &windowPoses, const PinholeIntrinsics &K,
                                                     const GlobalBundleOptions &options, int pointsPerKeyframe)
{
  auto job = std::make_unique<GlobalBundleJob>(K);
  job->options = options;
  for (const auto &w : windowPoses) {
    job->problem.addKeyframe(w.first, w.second, true);
  }
  for (const auto &entry : map.keyframes()) {
    const GlobalKeyframe &kf = entry.second;
    if (kf.segment == segment && !windowPoses.count(kf.id)) {
      job->problem.addKeyframe(kf.id, kf.cMw, false);
      job->keyframes.push_back(kf.id);
    }
  }
  auto measured = [&](const GlobalPoint &p) {
    int n = 0;
    for (size_t o = 0; o < p.observers.size() && o < p.observedAt.size(); ++o) {
      const bool inProblem = windowPoses.count(p.observers[o]) > 0 || map.find(p.observers[o]) != nullptr;
      n += inProblem && std::isfinite(p.observedAt[o][0]) ? 1 : 0;
    }
    return n;
  };
  std::vector<std::pair<int, size_t>> ranked; // (-(2 x measured observers + corner), index): best first
  for (int id : job->keyframes) {
    const GlobalKeyframe &kf = *map.find(id);
    ranked.clear();
    for (size_t i = 0; i < kf.points.size(); ++i) {
      const GlobalPoint &p = kf.points[i];
      const int n = p.state == GlobalPointState::stored && p.observedAt.size() == p.observers.size() ? measured(p) : 0;
      if (n > 0) {
        ranked.emplace_back(-(2 * n + (p.isCorner ? 1 : 0)), i);
      }
    }
    std::sort(ranked.begin(), ranked.end());
    if (pointsPerKeyframe > 0 && ranked.size() > static_cast<size_t>(pointsPerKeyframe)) {
      ranked.resize(static_cast<size_t>(pointsPerKeyframe));
    }
    for (const auto &r : ranked) {
      const size_t i = r.second;
      const GlobalPoint &p = kf.points[i];
      BundlePoint b;
      b.hostId = id;
      b.u = p.u;
      b.v = p.v;
      b.idepth = p.idepth;
      for (size_t o = 0; o < p.observers.size(); ++o) {
        b.observations.push_back({p.observers[o], p.observedAt[o][0], p.observedAt[o][1]});
      }
      const int index = job->problem.addPoint(b);
      if (index >= 0) {
        job->points.emplace_back(id, i);
        job->pointIndex.push_back(index);
      }
    }
  }
  return job;
}

std::vector<int> applyGlobalBundleJob(const GlobalBundleJob &job, GlobalMap &map)
{
  std::vector<int> moved;
  if (!job.summary.usable) {
    return moved;
  }
  for (int id : job.keyframes) {
    if (GlobalKeyframe *kf = map.findForChange(id)) {
      kf->cMw = job.problem.keyframe(id);
      moved.push_back(id);
    }
  }
  for (size_t k = 0; k < job.points.size(); ++k) {
    GlobalKeyframe *kf = map.findForChange(job.points[k].first);
    if (!kf || job.points[k].second >= kf->points.size()) {
      continue;
    }
    GlobalPoint &p = kf->points[job.points[k].second];
    if (p.state != GlobalPointState::stored) {
      continue; // re-used meanwhile: the window owns it now
    }
    const double before = p.idepth;
    const double after = job.problem.idepth(job.pointIndex[k]);
    // The variance follows the inverse depth as in a rescaling (relative uncertainty kept).
    p.idepthVar = static_cast<float>(p.idepthVar * (after / before) * (after / before));
    p.idepth = static_cast<float>(after);
  }
  return moved;
}

void BackgroundBundleAdjustment::start(std::unique_ptr<GlobalBundleJob> job)
{
  cancel();
  m_job = std::move(job);
  m_done = false;
  m_cancel = false;
  m_job->options.cancel = &m_cancel;
  GlobalBundleJob *running = m_job.get();
  m_thread = std::thread([this, running]() {
    running->run();
    m_done = true;
  });
}

std::unique_ptr<GlobalBundleJob> BackgroundBundleAdjustment::take()
{
  if (m_thread.joinable()) {
    m_thread.join();
  }
  if (m_job) {
    m_job->options.cancel = nullptr;
  }
  return std::move(m_job);
}

void BackgroundBundleAdjustment::cancel()
{
  m_cancel = true;
  if (m_thread.joinable()) {
    m_thread.join();
  }
  m_job.reset();
  m_done = false;
}
} // namespace hslam
