/*
 * H-SLAM for ViSP.
 */
/*!
  \file GlobalBundleJob.h
  \brief The global bundle adjustment of a map segment as a job: built from the global map, solved in the caller's
  thread (deterministic mode) or in the background (real time), then written back.

  What it is for: after a loop correction (paper sec. 3.4) the stored keyframes of the segment and their stored
  points are refined against the pixels their observers saw them at (GlobalPoint::observedAt). The window's keyframes
  are held (fixed): the window's priors stay valid and they hold the gauge. The job copies everything it needs, so
  the mapper goes on while it runs; a newer correction, which moves the same keyframes, cancels it before it could be
  written back (LocalMapper::correctLoop), so a job that ends is never stale.

  Threading: BackgroundBundleAdjustment runs at most one job on its own thread (the "third thread" of real-time
  mode); start / finished / take / cancel are called from one thread (the mapping thread).
*/
#ifndef HSLAM_LOOP_GLOBAL_BUNDLE_JOB_H
#define HSLAM_LOOP_GLOBAL_BUNDLE_JOB_H

#include "loop/GlobalBundleAdjustment.h"
#include "map/GlobalMap.h"

#include <atomic>
#include <map>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

namespace hslam
{
//! One global bundle adjustment: the problem built from the map, where each of its points came from, its result.
struct GlobalBundleJob {
  explicit GlobalBundleJob(const PinholeIntrinsics &K) : problem(K) {}
  GlobalBundleAdjustment problem;
  GlobalBundleOptions options;
  std::vector<int> keyframes;                 //!< stored keyframes it may move
  std::vector<std::pair<int, size_t>> points; //!< per problem point: (host id, index in its points)
  std::vector<int> pointIndex;                //!< per entry of points: index in the problem
  GlobalBundleSummary summary;                //!< filled by run()
  void run() { summary = problem.optimize(options); }
};

/*!
  The job for segment \e segment of \e map: its stored keyframes free, the window's keyframes (\e windowPoses, held)
  as further observers, and of each stored keyframe's stored points with a measured observer in the problem, the
  \e pointsPerKeyframe seen by the most keyframes (all when 0; ties: corners first). Every point takes part in the
  update of its host anyway: the others follow their host rigidly, their inverse depths unchanged.
*/
VISP_EXPORT std::unique_ptr<GlobalBundleJob>
makeGlobalBundleJob(const GlobalMap &map, int segment, const std::map<int, SE3d> &windowPoses,
                    const PinholeIntrinsics &K, const GlobalBundleOptions &options, int pointsPerKeyframe);

/*!
  Write a solved job back: the stored keyframes' poses and their points' inverse depths (points that left the global
  map since, re-activated or fused, keep theirs: the window owns them). Returns the keyframes moved. Nothing is
  written when the job's solution is not usable.
*/
VISP_EXPORT std::vector<int> applyGlobalBundleJob(const GlobalBundleJob &job, GlobalMap &map);

//! One job at a time on a thread of its own.
class VISP_EXPORT BackgroundBundleAdjustment
{
public:
  ~BackgroundBundleAdjustment() { cancel(); }
  //! Run \e job in the background; a job still running is cancelled first.
  void start(std::unique_ptr<GlobalBundleJob> job);
  bool running() const { return m_job != nullptr; }
  //! True when the running job has ended (take() does not wait).
  bool finished() const { return m_job && m_done.load(); }
  //! The ended job (waits for it when still running); null when none.
  std::unique_ptr<GlobalBundleJob> take();
  //! Stop the running job at its next iteration and drop it.
  void cancel();

private:
  std::unique_ptr<GlobalBundleJob> m_job;
  std::thread m_thread;
  std::atomic<bool> m_done{false};
  std::atomic<bool> m_cancel{false};
};
} // namespace hslam

#endif
