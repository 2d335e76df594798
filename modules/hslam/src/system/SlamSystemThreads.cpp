/*
 * H-SLAM for ViSP.
 */
// The conductor's threads and shared data (SlamSystem): the hand-over from tracking to mapping, deterministic (in the
// caller's thread) or through the real-time mapping thread's queue (DSO FullSystem::deliverTrackedFrame /
// mappingLoop), the back-end job and what it publishes for the tracking thread and the viewers; the map access the
// tracking components get (TrackingMap), and what the system gives out (any thread). See SlamSystem.h for the
// threading rules.
#include "system/SlamSystem.h"

#include "math/ViSPConversions.h"

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
  observeTags(id, *job.frame);
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
    m_metricFrame.rescaleKeyframes(correctedIds, correctedScales); // the tag's depths measured in those keyframes
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
  {
    std::lock_guard<std::mutex> lock(m_snapshotMutex);
    m_snapshotPoints.swap(points);
    m_snapshotImmature = static_cast<unsigned int>(m_mapper->immaturePointCount());
    m_snapshotReuse = m_mapper->reuseStatistics();
    m_snapshotLoopStats = m_mapper->loopStatistics();
  }
  publishMemory(false);
}

void SlamSystem::publishMemory(bool exact)
{
  // Counted outside the snapshot's lock: the tracking thread reads the statistics meanwhile.
  const double marginalizedBytes = m_mapper->marginalizedMemoryBytes(exact);
  const double windowBytes = m_mapper->windowMemoryBytes();
  const unsigned int held = static_cast<unsigned int>(m_mapper->keyframesHeld());
  const double descriptorKb = m_mapper->descriptorBytesPerKeyframe() / 1024.;
  std::lock_guard<std::mutex> lock(m_snapshotMutex);
  m_snapshotMemoryMb = (windowBytes + marginalizedBytes) / kBytesPerMegabyte;
  m_snapshotKeyframesHeld = held;
  m_snapshotDescriptorKb = descriptorKb;
  m_snapshotMarginalizedMb = marginalizedBytes / kBytesPerMegabyte;
}

void SlamSystem::finishBackgroundWork()
{
  synchronize();
  std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
  if (m_mapper->collectGlobalBundleAdjustment(true)) {
    publishAfterKeyframe();
  }
  publishMemory(true); // between keyframes the memory is an estimate (LocalMapper::marginalizedMemoryBytes)
}

void SlamSystem::synchronize()
{
  if (!m_mappingThread.joinable()) {
    return;
  }
  std::unique_lock<std::mutex> lock(m_queueMutex);
  m_jobDone.wait(lock, [this]() { return m_queue.empty() && !m_mappingBusy; });
}

std::vector<RelocalizationKeyframe> SlamSystem::relocalizationCandidates(RelocalizationFrame &frame, int maxCandidates,
                                                                         int preferred)
{
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  return m_mapper->relocalizationCandidates(frame, maxCandidates, preferred);
}

std::vector<WindowView> SlamSystem::windowViews()
{
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  return m_mapper->windowViews();
}

void SlamSystem::localMapFeatures(int id, std::vector<ReferenceFeature> &features, std::vector<int> &keyframeIds)
{
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  m_mapper->localMapFeatures(id, features, keyframeIds);
}

void SlamSystem::localMapReference(const std::vector<int> &keyframeIds, const SE3d &refMw,
                                   std::vector<CoarseTrackerPoint> &points)
{
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  m_mapper->localMapReference(keyframeIds, refMw, points);
}

int SlamSystem::closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds)
{
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  return m_mapper->closestKeyframe(cMw, keyframeIds);
}

void SlamSystem::observeTags(int keyframeId, const Frame &frame)
{
  // Called with m_mapperMutex held (runJob, initialisation): the window's points may be read.
  const MetricFrame::PoseLookup pose = [this](int id, SE3d &wMc) { return m_recorder.keptKeyframePose(id, wMc); };
  const MetricFrame::PointLookup points = [this](std::vector<Eigen::Vector3d> &p) { m_mapper->activePointsWorld(p); };
  m_metricFrame.observeKeyframe(keyframeId, m_segment, frame.raw, pose, points);
  const MetricFit fit = m_metricFrame.current();
  const unsigned int stored = m_metricFrame.sightingCount();
  if (!fit.metric || fit.allSegments) { // not metric (again: a new tag, a new segment): no constraints
    if (m_tagSightingsGiven != 0) {
      m_mapper->setLandmarkSightings(LandmarkSightings());
      m_tagSightingsGiven = 0;
    }
    return;
  }
  if (stored == m_tagSightingsGiven) {
    return;
  }
  // The tag's sightings as metric constraints of loop closure's pose graphs (nothing without a loop closer).
  m_tagSightingsGiven = stored;
  LandmarkSightings landmarks;
  landmarks.metresPerUnit = fit.scale;
  for (const MetricFrame::SegmentSighting &s : m_metricFrame.segmentSightings()) {
    landmarks.sightings.push_back({s.keyframeId, s.tagId, s.cMt, s.cMt.translation().norm()});
  }
  m_mapper->setLandmarkSightings(std::move(landmarks));
  if (m_metricFrame.seenAgain(keyframeId) && m_mapper->correctLandmarks(keyframeId)) {
    publishAfterKeyframe(); // the moved keyframes: trajectory, the tag's depth measurements in them
    m_metricFrame.refit(pose, points);
  }
}

vpHomogeneousMatrix SlamSystem::get_cMw() const
{
  SE3d wMc;
  if (m_recorder.lastFramePose(wMc)) {
    return toVpHomogeneousMatrix(outputPose(m_metricFrame.current(), wMc).inverse());
  }
  return vpHomogeneousMatrix();
}

bool SlamSystem::hasPose() const
{
  return m_recorder.frameCount() > 0;
}

std::vector<vpHSlam::Keyframe> SlamSystem::keyframes() const
{
  const std::vector<TrajectoryRecorder::KeyframeRecord> records = m_recorder.keyframes();
  const MetricFit fit = m_metricFrame.current();
  std::vector<vpHSlam::Keyframe> out;
  out.reserve(records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    if (records[i].discarded) {
      continue;
    }
    vpHSlam::Keyframe k;
    k.id = static_cast<unsigned int>(records[i].id);
    k.frameIndex = static_cast<unsigned int>(records[i].frameIndex);
    k.timestamp = records[i].timestamp;
    k.wMc =
        toVpHomogeneousMatrix(appliesTo(fit, records[i].segment) ? outputPose(fit, records[i].wMc) : records[i].wMc);
    k.inWindow = records[i].inWindow;
    k.segment = records[i].segment;
    k.activePoints = records[i].activePoints;
    out.push_back(k);
  }
  return out;
}

std::vector<vpColVector> SlamSystem::activePoints(std::vector<double> *depths) const
{
  std::vector<Eigen::Vector3d> points;
  {
    std::lock_guard<std::mutex> lock(m_snapshotMutex);
    points = m_snapshotPoints;
  }
  SE3d wMc;
  const bool havePose = m_recorder.lastFramePose(wMc);
  const SE3d cMw = wMc.inverse();
  const MetricFit fit = m_metricFrame.current();
  const double depthScale = fit.metric ? fit.scale : 1.;
  std::vector<vpColVector> out;
  out.reserve(points.size());
  if (depths) {
    depths->clear();
    depths->reserve(points.size());
  }
  for (const Eigen::Vector3d &p : points) {
    const Eigen::Vector3d o = outputPoint(fit, p);
    vpColVector v(3);
    v[0] = o.x();
    v[1] = o.y();
    v[2] = o.z();
    out.push_back(v);
    if (depths) {
      depths->push_back(depthScale * (havePose ? (cMw * p).z() : p.z()));
    }
  }
  return out;
}

vpHSlam::Statistics SlamSystem::statistics() const
{
  vpHSlam::Statistics s;
  s.frames = m_frames.load();
  s.trackedFrames = m_trackedFrames.load();
  s.keyframes = static_cast<unsigned int>(m_recorder.keyframeCount());
  s.segments = m_segmentsStarted;
  s.lostFrames = m_lostFrames.load();
  s.mappingSkippedFrames = m_mappingSkipped.load();
  const RunStatistics::Summary t = m_runStats.summary();
  s.trackingMsMedian = t.trackingMsMedian;
  s.trackingMsP95 = t.trackingMsP95;
  s.trackingMsMax = t.trackingMsMax;
  s.initializationMsMedian = t.initializationMsMedian;
  s.mappingMsPerKeyframeMedian = t.keyframeMsMedian;
  s.mappingMsPerKeyframeP95 = t.keyframeMsP95;
  s.mappingMsPerFrameMedian = t.frameMappingMsMedian;
  std::lock_guard<std::mutex> lock(m_snapshotMutex);
  s.activePoints = static_cast<unsigned int>(m_snapshotPoints.size());
  s.immaturePoints = m_snapshotImmature;
  s.mapMemoryMb = m_snapshotMemoryMb;
  s.keyframesHeld = m_snapshotKeyframesHeld;
  const LocalMapper::ReuseStatistics &r = m_snapshotReuse;
  s.marginalizedMemoryMb = m_snapshotMarginalizedMb;
  s.marginalizedKeyframes = static_cast<unsigned int>(r.storedKeyframes);
  // Per keyframe: what one more keyframe costs once it has left the window (the window's own keyframes are a
  // fixed cost); with nothing stored (vo-strict), the window's memory per keyframe.
  if (r.storedKeyframes > 0) {
    s.mapMemoryMbPerKeyframe = m_snapshotMarginalizedMb / r.storedKeyframes;
  } else {
    s.mapMemoryMbPerKeyframe = m_snapshotKeyframesHeld > 0 ? m_snapshotMemoryMb / m_snapshotKeyframesHeld : 0.;
  }
  s.culledKeyframes = static_cast<unsigned int>(r.culledKeyframes);
  s.globalPoints = static_cast<unsigned int>(r.storedPoints);
  s.reactivatedPointsPerKeyframe = r.keyframes > 0 ? static_cast<double>(r.reactivated) / r.keyframes : 0.;
  s.fusedPointsPerKeyframe = r.keyframes > 0 ? static_cast<double>(r.fused) / r.keyframes : 0.;
  const LocalMapper::LoopStatistics &loops = m_snapshotLoopStats;
  s.loopsDetected = static_cast<unsigned int>(loops.loops.size());
  s.loopCandidatesVerified = static_cast<unsigned int>(loops.candidatesVerified);
  s.loopsCorrected = static_cast<unsigned int>(loops.applied.corrected);
  s.tagCorrections = static_cast<unsigned int>(loops.applied.landmarkCorrected);
  s.lastLoopCorrectionMs = loops.applied.lastCorrectionMs;
  s.loopCorrectionMsMax = loops.applied.correctionMsMax;
  s.loopDetectionMsMean = loops.detections > 0 ? loops.detectionMsTotal / loops.detections : 0.;
  s.loopDetections = static_cast<unsigned int>(loops.detections);
  s.loopVerificationMsMax = loops.verificationMsMax;
  s.loopVerificationMsMean = loops.detections > 0 ? loops.verificationMsTotal / loops.detections : 0.;
  s.globalBundleAdjustments = static_cast<unsigned int>(loops.applied.globalBaStarted);
  s.globalBundleAdjustmentsApplied = static_cast<unsigned int>(loops.applied.globalBaApplied);
  s.globalBundleAdjustmentSecondsMax = loops.applied.globalBaSecondsMax;
  s.globalBundleAdjustmentRmsBeforePx = loops.applied.globalBaRmsBeforePx;
  s.globalBundleAdjustmentRmsAfterPx = loops.applied.globalBaRmsAfterPx;
  s.framesDuringLoopCorrection = static_cast<unsigned int>(t.framesDuringLoopCorrection);
  s.trackingMsMaxDuringLoopCorrection = t.trackingMsMaxDuringLoopCorrection;
  s.windowShareFromGlobal = r.windowActive > 0 ? static_cast<double>(r.windowFromGlobal) / r.windowActive : 0.;
  s.orbMatchesMedian = t.orbMatchesMedian;
  s.orbInliersMedian = t.orbInliersMedian;
  s.geometricWeightMedian = t.geometricWeightMedian;
  s.geometricTermFrames = static_cast<unsigned int>(t.geometricFrames);
  s.geometricTermShare = t.posedFrames > 0 ? static_cast<double>(t.geometricFrames) / t.posedFrames : 0.;
  s.adaptiveLargeMotionFrames = static_cast<unsigned int>(t.geometricLargeMotion);
  s.adaptivePredictionRefusedFrames = static_cast<unsigned int>(t.geometricPredictionRefused);
  s.adaptiveDirectFailedFrames = static_cast<unsigned int>(t.geometricDirectFailed);
  s.relocalizationsAttempted = m_relocAttempts.load();
  s.relocalizationsSucceeded = m_relocSuccesses.load();
  s.descriptorKbPerKeyframe = m_snapshotDescriptorKb;
  const MetricFit fit = m_metricFrame.current();
  s.metric = fit.metric;
  s.tagSightings = m_metricFrame.sightingCount();
  s.tagSightingsUsed = fit.kept;
  s.metricScale = fit.scale;
  s.metricScaleUncertainty = fit.scaleUncertainty;
  s.tagDetectionMsMean = m_metricFrame.detectionMsMean();
  return s;
}

void SlamSystem::setTag(const vpHSlamTag &tag)
{
  m_metricFrame.setTag(tag, m_params.tagFrame, m_preprocessor.getCameraParameters());
}

vpHSlamTag SlamSystem::tag() const
{
  return m_metricFrame.tag();
}

vpHSlam::WorldFrame SlamSystem::worldFrame() const
{
  const MetricFit fit = m_metricFrame.current();
  vpHSlam::WorldFrame w;
  w.metric = fit.metric;
  w.tagFrame = fit.metric && fit.tagFrame;
  w.scale = fit.scale;
  w.scaleUncertainty = fit.scaleUncertainty;
  w.rmsMetres = fit.rmsMetres;
  w.sightings = m_metricFrame.sightingCount();
  w.sightingsUsed = fit.kept;
  if (fit.metric) {
    double scale = 1.;
    w.oMw = toVpHomogeneousMatrix(fit.mSw, scale);
  }
  return w;
}

std::vector<vpHSlam::MapPoint> SlamSystem::mapPoints() const
{
  std::vector<Eigen::Vector3d> points;
  std::vector<int> status;
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    if (m_mapper) {
      m_mapper->mapPointsWorld(points, status);
    }
  }
  const MetricFit fit = m_metricFrame.current();
  std::vector<vpHSlam::MapPoint> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d o = outputPoint(fit, points[i]);
    out[i].wX.resize(3);
    for (unsigned int k = 0; k < 3; ++k) {
      out[i].wX[k] = o[static_cast<int>(k)];
    }
    out[i].active = status[i] == 0;
  }
  return out;
}

std::vector<vpHSlam::GraphEdge> SlamSystem::graphEdges() const
{
  std::vector<vpHSlam::GraphEdge> out;
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  if (!m_mapper) {
    return out;
  }
  const GlobalMap &map = m_mapper->globalMap();
  for (const CovisibilityEdge &e : map.covisibilityEdges()) {
    vpHSlam::GraphEdge g;
    g.a = static_cast<unsigned int>(e.a);
    g.b = static_cast<unsigned int>(e.b);
    g.covisibility = true;
    g.weight = static_cast<unsigned int>(e.weight);
    out.push_back(g);
  }
  for (const PosePoseEdge &e : map.posePoseEdges()) {
    vpHSlam::GraphEdge g;
    g.a = static_cast<unsigned int>(e.from);
    g.b = static_cast<unsigned int>(e.to);
    out.push_back(g);
  }
  return out;
}

void SlamSystem::rectifiedImage(vpImage<unsigned char> &I) const
{
  std::lock_guard<std::mutex> lock(m_imageMutex);
  I = m_lastImage;
}
} // namespace hslam
