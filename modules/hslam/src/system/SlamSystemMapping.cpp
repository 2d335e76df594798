/*
 * H-SLAM for ViSP.
 */
// The hand-over from tracking to mapping: deterministic (in the caller's thread) or through the real-time mapping
// thread's queue (DSO FullSystem::deliverTrackedFrame / mappingLoop), the back-end job itself and what it publishes
// for the tracking thread and the viewers. See SlamSystem.h for the threading rules.
#include "system/SlamSystem.h"

#include "system/LocalMapper.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>

namespace hslam
{
namespace
{
//! Real-time mode: more queued frames than this and mapping catches up (DSO mappingLoop: more than 3).
constexpr size_t kCatchUpQueueLength = 3;
//! Real-time mode: frames queued for mapping at most (each holds its pyramid, several MB).
constexpr size_t kMaxQueuedFrames = 8;
constexpr double kBytesPerMegabyte = 1024. * 1024.;
} // namespace

void SlamSystem::startMappingThread()
{
  m_stopMapping = false;
  m_mappingThread = std::thread(&SlamSystem::mappingLoop, this);
}

void SlamSystem::stopMappingThread()
{
  if (!m_mappingThread.joinable()) {
    return;
  }
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    m_stopMapping = true;
  }
  m_queueChanged.notify_all();
  m_mappingThread.join();
}

void SlamSystem::deliver(MappingJob job)
{
  if (m_params.system.deterministic) {
    std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
    m_cpuLastJob = runJob(job);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    if (job.needKeyframe) {
      m_pendingKeyframeRef = std::max(m_pendingKeyframeRef, job.referenceKeyframe);
    }
    if (job.seedKeyframe >= 0) {
      m_pendingSeedKeyframe = job.seedKeyframe; // served by the keyframe made next, whichever frame it is
    }
    m_pendingRelocalization = m_pendingRelocalization || job.relocalized; // a skipped job must not lose it
    m_queue.push_back(std::move(job));
    // Bounded memory when mapping falls far behind: the oldest queued frames are dropped for mapping (their
    // keyframe request survives in m_pendingKeyframeRef; they keep their tracked pose).
    while (m_queue.size() > kMaxQueuedFrames) {
      m_queue.pop_front();
      ++m_mappingSkipped;
    }
  }
  m_queueChanged.notify_one();
}

void SlamSystem::mappingLoop()
{
  // Real-time mapping (DSO FullSystem::mappingLoop): never blocks tracking; when frames pile up, non-keyframes are
  // traced only when the queue is short, otherwise skipped, and a requested keyframe is made from the newest frame.
  std::unique_lock<std::mutex> lock(m_queueMutex);
  bool catchingUp = false;
  while (true) {
    m_queueChanged.wait(lock, [this]() { return m_stopMapping || !m_queue.empty(); });
    if (m_queue.empty()) {
      return; // stop requested and nothing left
    }
    MappingJob job = std::move(m_queue.front());
    m_queue.pop_front();
    if (m_queue.size() > kCatchUpQueueLength) {
      catchingUp = true;
    }
    bool makeKeyframe = false;
    if (!m_queue.empty()) {
      // Newer frames wait: this one is only traced (if we are not behind); keyframe requests wait for the newest.
      if (catchingUp) {
        ++m_mappingSkipped;
        m_jobDone.notify_all();
        continue;
      }
    } else {
      // DSO: a keyframe is made from the newest frame if some frame requested one while tracked against the
      // current newest keyframe (requests against an older reference were already served).
      makeKeyframe = m_pendingKeyframeRef >= 0 && m_pendingKeyframeRef >= m_keyframeCount.load() - 1;
      m_pendingKeyframeRef = -1;
      catchingUp = false;
    }
    job.needKeyframe = makeKeyframe;
    job.seedKeyframe = makeKeyframe ? m_pendingSeedKeyframe : -1;
    if (makeKeyframe) {
      m_pendingSeedKeyframe = -1;
    }
    job.relocalized = m_pendingRelocalization;
    m_pendingRelocalization = false;
    m_mappingBusy = true;
    lock.unlock();
    {
      std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
      runJob(job);
    }
    lock.lock();
    m_mappingBusy = false;
    m_jobDone.notify_all();
  }
}

double SlamSystem::runJob(const MappingJob &job)
{
  const double t0 = nowMs();
  const double c0 = threadCpuMs();
  // The reference keyframe may have moved since tracking: re-anchor (DSO makeKeyFrame / makeNonKeyFrame).
  const SE3d wMref = m_recorder.keyframePose(job.referenceKeyframe);
  job.frame->cMw = (wMref * job.refMc).inverse();
  if (job.relocalized) {
    m_mapper->noteRelocalization();
  }
  if (!job.needKeyframe) {
    m_mapper->makeNonKeyframe(job.frame);
    m_runStats.addFrameMappingMs(nowMs() - t0);
    const double cpu = threadCpuMs() - c0;
    m_cpuMapFrames += cpu;
    return cpu;
  }
  const int id = m_keyframeCount.fetch_add(1);
  m_recorder.addKeyframe(id, job.frame->id, job.frame->timestamp, wMref * job.refMc, m_segment);
  m_recorder.addFrame(job.frame->id, job.frame->timestamp, id, SE3d(), m_segment);
  m_mapper->makeKeyframe(job.frame, id, job.seedKeyframe);
  publishAfterKeyframe();
  m_runStats.addKeyframeMappingMs(nowMs() - t0);
  const double cpu = threadCpuMs() - c0;
  m_cpuMapKeyframes += cpu;
  if (m_mapper->initializationFailed()) {
    m_restartRequested = true;
    VP_HSLAM_LOG(vpHSlamLog::warning, "keyframe " << id << ": window residual too high for a correct "
                                                  << "initialisation; the map will be initialised again");
  }
  return cpu;
}

void SlamSystem::publishAfterKeyframe()
{
  std::vector<LocalMapper::KeyframeState> states;
  m_mapper->takeKeyframeStates(states);
  std::vector<int> correctedIds;
  std::vector<SE3d> correctedPoses;
  std::vector<double> correctedScales;
  for (const LocalMapper::KeyframeState &k : states) {
    if (k.scale != 1.) { // a loop correction scaled this keyframe's map: its frames follow
      correctedIds.push_back(k.id);
      correctedPoses.push_back(k.wMc);
      correctedScales.push_back(k.scale);
    } else {
      m_recorder.updateKeyframe(k.id, k.wMc);
    }
    m_recorder.setKeyframeInWindow(k.id, k.inWindow, k.activePoints);
  }
  if (!correctedIds.empty()) {
    m_recorder.correctKeyframes(correctedIds, correctedPoses, correctedScales);
  }
  {
    std::lock_guard<std::mutex> lock(m_referenceMutex);
    int id = -1;
    AffineBrightness affine;
    double exposure = 1.;
    if (m_mapper->prepareTrackingReference(*m_preparedTracker, id, affine, exposure)) {
      m_preparedRefKeyframe = id;
      m_preparedRefAffine = affine;
      m_preparedRefExposure = exposure;
      m_preparedReady = true;
    }
  }
  std::vector<Eigen::Vector3d> points;
  m_mapper->activePointsWorld(points);
  std::lock_guard<std::mutex> lock(m_snapshotMutex);
  m_snapshotPoints.swap(points);
  m_snapshotImmature = static_cast<unsigned int>(m_mapper->immaturePointCount());
  // The stored map is walked once per keyframe (its points' observer lists).
  const double marginalizedBytes = m_mapper->marginalizedMemoryBytes();
  m_snapshotMemoryMb = (m_mapper->windowMemoryBytes() + marginalizedBytes) / kBytesPerMegabyte;
  m_snapshotKeyframesHeld = static_cast<unsigned int>(m_mapper->keyframesHeld());
  m_snapshotDescriptorKb = m_mapper->descriptorBytesPerKeyframe() / 1024.;
  m_snapshotMarginalizedMb = marginalizedBytes / kBytesPerMegabyte;
  m_snapshotReuse = m_mapper->reuseStatistics();
  m_snapshotLoopStats = m_mapper->loopStatistics();
}

void SlamSystem::finishBackgroundWork()
{
  synchronize();
  std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
  if (m_mapper->collectGlobalBundleAdjustment(true)) {
    publishAfterKeyframe();
  }
}

void SlamSystem::synchronize()
{
  if (!m_mappingThread.joinable()) {
    return;
  }
  std::unique_lock<std::mutex> lock(m_queueMutex);
  m_jobDone.wait(lock, [this]() { return m_queue.empty() && !m_mappingBusy; });
}

} // namespace hslam
