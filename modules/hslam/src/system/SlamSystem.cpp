/*
 * H-SLAM for ViSP.
 */
// The conductor's tracking side (SlamSystem, the caller's thread): construction, the per-frame order of the
// components, segments, reset, map files. See SlamSystem.h.
#include "system/SlamSystem.h"

#include "features/OrbVocabulary.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace hslam
{
namespace
{
//! Relative tolerance on the intrinsics a loaded map must share with the system (both went through a text file).
constexpr double kIntrinsicsTolerance = 1e-6;

std::string where(int line)
{
  return std::string(__FILE__) + ":" + std::to_string(line) + ": ";
}

bool close(double a, double b)
{
  return std::fabs(a - b) <= kIntrinsicsTolerance * std::max(1., std::fabs(a));
}

std::string describe(const MapCamera &c)
{
  char text[160];
  std::snprintf(text, sizeof(text), "%dx%d, fx %.6g fy %.6g cx %.6g cy %.6g", c.width, c.height, c.fx, c.fy, c.cx,
                c.cy);
  return text;
}

std::string hex(std::uint64_t id)
{
  char text[24];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(id));
  return text;
}
} // namespace

SlamSystem::SlamSystem(const vpHSlamCamera &camera, const vpHSlamParameters &parameters,
                       const vpHSlamPhotometricCalibration &photometric)
    : m_params(parameters),
      m_preprocessor(camera, photometric, parameters.system.usePhotometricCalibration, parameters.tracker)
{
  m_params.validate();
  const bool calibrated = m_preprocessor.usesPhotometricCalibration();
  const PinholeIntrinsics &K = m_preprocessor.intrinsics();
  TrackingMap &map = *this; // what the tracking components may read of the back end
  m_initializer = std::make_unique<MonocularInitializer>(m_params, K, calibrated);
  m_preparedTracker = std::make_unique<CoarseTracker>(m_params.tracker, calibrated);
  // Relocalisation needs the keyframe database: with hybrid / indirect tracking, and with direct tracking in the
  // modes that keep a global map (vo-reuse, slam), where a lost camera is found again in the stored keyframes.
  const bool direct = m_params.tracking.mode == vpHSlamParameters::trackingDirect;
  const bool relocalizes =
      m_params.tracking.relocalize && (!direct || LocalMapper::keepsGlobalMap(m_params.system.mode));
  // The vocabulary: relocalisation, loop detection (slam mode) and localisation in a loaded map.
  if (relocalizes || m_params.system.mode == vpHSlamParameters::modeSlam || m_params.system.localizationOnly) {
    const std::string path = vpHSlamVocabulary::defaultPath();
    if (path.empty()) {
      VP_HSLAM_LOG(vpHSlamLog::warning,
                   "no vocabulary found (set HSLAM_VOCABULARY to a vocabulary file): "
                       << (m_params.system.mode == vpHSlamParameters::modeSlam ? "loop closure and relocalisation are"
                                                                               : "relocalisation is")
                       << " off, a lost camera starts a new map segment");
    } else {
      m_vocabulary = std::make_unique<vpHSlamVocabulary>(vpHSlamVocabulary::load(path));
    }
  }
  m_mapper = std::make_unique<LocalMapper>(m_params, K, m_preprocessor.width(), m_preprocessor.height(), calibrated,
                                           m_vocabulary ? &m_vocabulary->impl() : nullptr);
  // The frame's ORB features: hybrid / indirect tracking, localisation-only, and relocalisation with direct tracking
  // (frames are then described only while the camera is lost).
  if (!direct || m_params.system.localizationOnly || relocalizes) {
    m_hybrid = std::make_unique<HybridTracker>(m_params, K, m_preprocessor.width(), m_preprocessor.height());
    m_relocalizer = std::make_unique<LostFrameRelocalizer>(m_params.tracking, K, *m_hybrid, map);
    m_localizer = std::make_unique<MapLocalizer>(m_params, K, calibrated, *m_hybrid, map);
  }
  m_frameTracker = std::make_unique<FrameTracker>(m_params, calibrated, m_preprocessor.width(), m_preprocessor.height(),
                                                  m_hybrid.get());
  const bool seedFromStoredMap =
      m_params.tracking.seedFromStoredMap && m_mapper->keepsGlobalMap() && m_params.globalMap.reuse;
  m_tracking =
      std::make_unique<TrackingStateMachine>(m_params, *m_frameTracker, m_relocalizer.get(), map, seedFromStoredMap,
                                             m_vocabulary != nullptr && m_params.tracking.relocalize);
  if (!m_params.system.deterministic) {
    startMappingThread();
  }
}

SlamSystem::~SlamSystem()
{
  stopMappingThread();
  VP_HSLAM_LOG(vpHSlamLog::debug, "CPU time (ms): preprocessing " << m_cpuPreprocess << ", initialisation "
                                                                  << m_cpuInitialize << ", tracking " << m_cpuTrack
                                                                  << ", mapping keyframes " << m_cpuMapKeyframes
                                                                  << ", mapping other frames " << m_cpuMapFrames);
}

vpHSlam::State SlamSystem::track(const vpImage<unsigned char> &I, double timestamp, double exposure)
{
  if (!std::isfinite(timestamp)) {
    std::ostringstream msg;
    msg << where(__LINE__) << "timestamp " << timestamp << " s of frame " << m_nextFrameId << " is not finite";
    throw vpHSlamException(vpHSlamException::invalidTimestamps, msg.str());
  }
  if (m_frames.load() > 0 && !(timestamp > m_lastTimestamp)) {
    std::ostringstream msg;
    msg << where(__LINE__) << "timestamp " << timestamp << " s of frame " << m_nextFrameId
        << " does not increase (previous " << m_lastTimestamp << " s)";
    throw vpHSlamException(vpHSlamException::invalidTimestamps, msg.str());
  }
  if (m_params.system.localizationOnly && !m_localizationReady) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(__LINE__) + "system.localizationOnly: load a map (loadMap) before the first frame");
  }
  const double t0 = nowMs();
  m_frameStartMs = t0;
  const bool correctingLoopBefore = m_mapper->correctingLoop(); // an atomic: no lock, tracking never waits here
  const double c0 = threadCpuMs();
  FramePtr frame = m_preprocessor.process(I, timestamp, exposure, m_nextFrameId);
  const double c1 = threadCpuMs();
  m_cpuPreprocess += c1 - c0;
  ++m_nextFrameId;
  ++m_frames;
  m_lastTimestamp = timestamp;
  {
    std::lock_guard<std::mutex> lock(m_imageMutex);
    m_lastImage = frame->raw;
  }
  vpHSlam::State state;
  if (m_params.system.localizationOnly) {
    state = localize(frame);
    m_cpuTrack += threadCpuMs() - c1;
  } else if (m_tracking->phase() == TrackingStateMachine::Phase::newSegment) {
    state = initialize(frame, I, exposure);
    m_runStats.addInitializationMs(nowMs() - t0);
    m_cpuInitialize += threadCpuMs() - c1;
  } else {
    m_cpuLastJob = 0.;
    state = trackInitialized(frame); // records its own tracking time (mapping excluded)
    m_cpuTrack += threadCpuMs() - c1 - (m_params.system.deterministic ? m_cpuLastJob : 0.);
  }
  if (!m_params.system.deterministic && (correctingLoopBefore || m_mapper->correctingLoop())) {
    m_runStats.addTrackingMsDuringLoopCorrection(nowMs() - t0); // real time: the frame overlapped a correction
  }
  if (state == vpHSlam::stateTracking) {
    ++m_trackedFrames;
  } else if (state == vpHSlam::stateLost) {
    ++m_lostFrames;
  }
  m_state = state;
  return state;
}

vpHSlam::State SlamSystem::localize(const FramePtr &frame)
{
  const MapLocalizer::Result r = m_localizer->localize(frame);
  m_relocAttempts += r.recognitionTried ? 1 : 0;
  m_relocSuccesses += r.recognized ? 1 : 0;
  m_runStats.addTrackingMs(nowMs() - m_frameStartMs);
  if (!r.located) {
    return vpHSlam::stateLost;
  }
  // Anchored to the world (no keyframe of this run): the trajectory is in the loaded map's coordinates.
  m_recorder.addFrame(frame->id, frame->timestamp, -1, r.cMw.inverse(), m_segment);
  return vpHSlam::stateTracking;
}

vpHSlam::State SlamSystem::initialize(const FramePtr &frame, const vpImage<unsigned char> &I, double exposure)
{
  if (!m_initializer->addFrame(frame, I, exposure)) {
    return vpHSlam::stateInitializing;
  }
  // Nothing is queued for mapping while initialising: the back end is idle and may be driven from here.
  synchronize();
  std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
  if (!makeFirstMap(frame)) {
    return vpHSlam::stateInitializing;
  }
  publishAfterKeyframe();
  observeTags(m_keyframeCount.load() - 2, *m_initializer->firstFrame());
  observeTags(m_keyframeCount.load() - 1, *frame);
  adoptPreparedReference();
  backfill(m_initializer->result(), frame->id);
  m_initializer->reset();
  m_frameTracker->startSegment(frame->affine);
  // The frame before the second keyframe, when it has a pose (the first keyframe, or tracked backwards), gives the
  // next frame its velocity: starting from no motion, every third KITTI frame (3.6 m ahead) converged to a camera
  // that had hardly moved.
  SE3d wMbefore;
  m_tracking->startSegment(frame->id, m_recorder.framePose(frame->id - 1, wMbefore) ? frame->id - 1 : -1);
  ++m_segmentsStarted;
  return vpHSlam::stateTracking;
}

bool SlamSystem::makeFirstMap(const FramePtr &frame)
{
  const TwoViewInitialization &init = m_initializer->result();
  const FramePtr first = m_initializer->firstFrame();
  const int firstId = m_keyframeCount.load();
  if (!m_mapper->initialize(first, firstId, frame, firstId + 1, init, m_segmentOrigin)) {
    VP_HSLAM_LOG(vpHSlamLog::info, "initialisation from frames " << init.firstFrameId << " and " << frame->id
                                                                 << " gave too few points; trying again");
    m_mapper->clear();
    m_initializer->restartFrom(frame);
    return false;
  }
  m_keyframeCount += 2;
  m_recorder.addKeyframe(firstId, first->id, first->timestamp, first->cMw.inverse(), m_segment);
  m_recorder.addKeyframe(firstId + 1, frame->id, frame->timestamp, frame->cMw.inverse(), m_segment);
  m_recorder.addFrame(first->id, first->timestamp, firstId, SE3d(), m_segment);
  m_recorder.addFrame(frame->id, frame->timestamp, firstId + 1, SE3d(), m_segment);
  if (first->id != frame->id) {
    ++m_trackedFrames; // the first frame got its pose now
  }
  VP_HSLAM_LOG(vpHSlamLog::info, "initialised from frames " << init.firstFrameId << " and " << frame->id << " ("
                                                            << init.points.size() << " points, parallax "
                                                            << init.parallaxDeg << " deg), segment " << m_segment);
  return true;
}

void SlamSystem::backfill(const TwoViewInitialization &init, int secondFrameId)
{
  const int secondKeyframe = m_keyframeCount.load() - 1;
  const auto setReference = [&](CoarseTracker &tracker, AffineBrightness &affine) {
    int id = -1;
    double exposure = 1.;
    return m_mapper->prepareTrackingReference(tracker, id, affine, exposure) && id == secondKeyframe;
  };
  const auto preprocess = [&](const MonocularInitializer::PendingFrame &p) {
    return m_preprocessor.process(p.I, p.timestamp, p.exposure, p.id);
  };
  for (const MonocularInitializer::BackfilledFrame &f :
       m_initializer->backfill(init.c2Mc1, init.firstFrameId, secondFrameId, setReference, preprocess)) {
    m_recorder.addFrame(f.id, f.timestamp, secondKeyframe, f.refMc, m_segment);
    ++m_trackedFrames;
  }
}

vpHSlam::State SlamSystem::trackInitialized(const FramePtr &frame)
{
  const double t0 = m_frameStartMs; // tracking time includes the preprocessing of the frame
  if (m_restartRequested.exchange(false)) {
    declareLost(true);
    return vpHSlam::stateInitializing; // the map is started again: not a loss of tracking
  }
  adoptPreparedReference();
  const int referenceKeyframe = m_frameTracker->referenceKeyframe();
  const TrackingStateMachine::Outcome out = m_tracking->track(frame);
  for (const FrameTracker::HybridStep &s : m_frameTracker->takeHybridSteps()) {
    m_runStats.addHybridFrame(s.matches, s.inliers, s.geometricWeight);
  }
  m_relocAttempts += out.relocalizationAttempted ? 1 : 0;
  m_relocSuccesses += out.relocalized ? 1 : 0;
  if (out.report == TrackingStateMachine::Outcome::endSegment) {
    declareLost();
  }
  if (out.report != TrackingStateMachine::Outcome::tracked) {
    m_runStats.addTrackingMs(nowMs() - t0);
    return vpHSlam::stateLost;
  }
  m_recorder.addFrame(frame->id, frame->timestamp, referenceKeyframe, out.refMc, m_segment);
  m_runStats.addTrackingMs(nowMs() - t0);
  m_runStats.addPosedFrame(out.aligned ? m_frameTracker->lastReason() : GeometricReason::none);
  if (out.aligned) {
    MappingJob job;
    job.frame = frame;
    job.referenceKeyframe = referenceKeyframe;
    job.refMc = out.refMc;
    job.needKeyframe = out.needKeyframe;
    job.seedKeyframe = out.seedKeyframe;
    job.relocalized = out.relocalized;
    deliver(std::move(job));
  }
  return vpHSlam::stateTracking;
}

void SlamSystem::adoptPreparedReference()
{
  std::unique_lock<std::mutex> lock(m_referenceMutex, std::try_to_lock);
  if (!lock.owns_lock() || !m_preparedReady) {
    return; // the back end is preparing one: keep the current reference for this frame
  }
  m_frameTracker->adoptReference(m_preparedTracker, m_preparedRefKeyframe, m_preparedRefAffine, m_preparedRefExposure);
  m_preparedReady = false;
}

void SlamSystem::declareLost(bool discardSegment)
{
  // Keep the old segment (trajectory, keyframes) and chain the next one to the last known pose; a segment whose
  // initialisation proved wrong is discarded instead (DSO resets after a failed initialisation).
  synchronize();
  m_tracking->endSegment();
  {
    std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
    // A global bundle adjustment still running on the closing segment is waited for and written back (its keyframes
    // stay in the global map): a new segment would otherwise drop what it computed. The statistics snapshot is
    // refreshed here: the new segment may publish no keyframe before the run ends (the real-time loop test under
    // ThreadSanitizer once ended with three adjustments started, the last written back here, and none reported).
    if (m_mapper->collectGlobalBundleAdjustment(true)) {
      std::lock_guard<std::mutex> lock(m_snapshotMutex);
      m_snapshotLoopStats = m_mapper->loopStatistics();
    }
    std::vector<LocalMapper::KeyframeState> states;
    m_mapper->takeKeyframeStates(states);
    for (const LocalMapper::KeyframeState &k : states) {
      m_recorder.updateKeyframe(k.id, k.wMc);
      m_recorder.setKeyframeInWindow(k.id, false, 0);
    }
    m_mapper->clear();
  }
  dropPreparedReferenceAndSnapshot();
  if (discardSegment) {
    const size_t removed = m_recorder.discardSegment(m_segment);
    m_trackedFrames -= static_cast<unsigned int>(std::min<size_t>(removed, m_trackedFrames.load()));
    if (m_segmentsStarted.load() > 0) {
      --m_segmentsStarted;
    }
  } else {
    SE3d wMlast;
    if (m_recorder.lastFramePose(wMlast)) {
      m_segmentOrigin = wMlast;
    }
  }
  m_frameTracker->dropReference();
  m_initializer->reset();
  if (!discardSegment) {
    ++m_segment; // a discarded segment's number is used again
  }
  m_metricFrame.startSegment(m_segment); // the new segment has its own scale: not metric until the tag is seen in it
}

void SlamSystem::dropPreparedReferenceAndSnapshot()
{
  {
    std::lock_guard<std::mutex> lock(m_referenceMutex);
    m_preparedReady = false;
  }
  std::lock_guard<std::mutex> lock(m_snapshotMutex);
  m_snapshotPoints.clear();
  m_snapshotImmature = 0;
  m_snapshotMemoryMb = 0.;
  m_snapshotKeyframesHeld = 0;
}

void SlamSystem::reset()
{
  synchronize();
  m_tracking->endSegment(); // keyframe ids start again: features kept by id would belong to other images
  {
    std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
    m_mapper->reset(); // the global map too: a reset system starts from nothing (keyframe ids start again at 0)
  }
  dropPreparedReferenceAndSnapshot();
  m_recorder.clear();
  m_runStats.clear();
  m_metricFrame.clear();
  m_tagSightingsGiven = 0;
  m_initializer->reset();
  m_frameTracker->reset();
  if (m_localizer) {
    m_localizer->reset(); // the loaded map went with the rest
  }
  m_localizationReady = false;
  m_segment = 0;
  m_segmentOrigin = SE3d();
  m_nextFrameId = 0;
  m_lastTimestamp = 0.;
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    m_pendingKeyframeRef = -1;
    m_pendingSeedKeyframe = -1;
    m_pendingRelocalization = false;
  }
  m_state = vpHSlam::stateInitializing;
  m_frames = 0;
  m_trackedFrames = 0;
  m_lostFrames = 0;
  m_mappingSkipped = 0;
  m_keyframeCount = 0;
  m_segmentsStarted = 0;
  m_restartRequested = false;
  m_relocAttempts = 0;
  m_relocSuccesses = 0;
  std::lock_guard<std::mutex> lock(m_imageMutex);
  m_lastImage.resize(0, 0);
}

MapCamera SlamSystem::mapCamera() const
{
  MapCamera c;
  c.width = m_preprocessor.width();
  c.height = m_preprocessor.height();
  c.fx = m_preprocessor.intrinsics().fx;
  c.fy = m_preprocessor.intrinsics().fy;
  c.cx = m_preprocessor.intrinsics().cx;
  c.cy = m_preprocessor.intrinsics().cy;
  return c;
}

void SlamSystem::requireGlobalMap(const std::string &path, const char *operation) const
{
  if (m_params.system.mode == vpHSlamParameters::modeVoStrict && !m_params.system.localizationOnly) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": " + operation +
                               " needs system.mode vo-reuse or slam (vo-strict discards the keyframes that leave the "
                               "window, so there is no map to keep)");
  }
}

void SlamSystem::checkLoadedMap(const std::string &path, const MapSnapshot &map) const
{
  const MapCamera mine = mapCamera();
  if (map.camera.width != mine.width || map.camera.height != mine.height || !close(map.camera.fx, mine.fx) ||
      !close(map.camera.fy, mine.fy) || !close(map.camera.cx, mine.cx) || !close(map.camera.cy, mine.cy)) {
    throw vpHSlamException(vpHSlamException::invalidCalibration,
                           path + ": the map was built with another camera (" + describe(map.camera) +
                               ") than this system's rectified camera (" + describe(mine) + ")");
  }
  if (map.vocabularyId != 0 && m_vocabulary && map.vocabularyId != m_vocabulary->impl().fingerprint()) {
    throw vpHSlamException(vpHSlamException::unsupported, path + ": the map was indexed with vocabulary " +
                                                              hex(map.vocabularyId) + ", this system uses vocabulary " +
                                                              hex(m_vocabulary->impl().fingerprint()) +
                                                              " (HSLAM_VOCABULARY or the shipped default)");
  }
}

void SlamSystem::saveMap(const std::string &path)
{
  requireGlobalMap(path, "saveMap");
  finishBackgroundWork(); // the map as the background bundle adjustment leaves it
  MapSnapshot map;
  map.camera = mapCamera();
  map.vocabularyId = m_vocabulary ? m_vocabulary->impl().fingerprint() : 0;
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    m_mapper->mapSnapshot(map.keyframes, map.edges);
  }
  if (map.keyframes.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, path + ": no map to save yet (no keyframe)");
  }
  map.metric = toMapMetricFrame(m_metricFrame.current());
  saveMapFile(path, map);
  VP_HSLAM_LOG(vpHSlamLog::info, "map saved to " << path << ": " << map.keyframes.size() << " keyframes, "
                                                 << map.edges.size() << " pose-pose edges");
}

void SlamSystem::loadMap(const std::string &path)
{
  requireGlobalMap(path, "loadMap");
  if (m_frames.load() > 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": loadMap comes before the first frame (or after reset())");
  }
  MapSnapshot map = loadMapFile(path);
  checkLoadedMap(path, map);
  int lastId = -1;
  for (const GlobalKeyframe &kf : map.keyframes) {
    lastId = std::max(lastId, kf.id);
  }
  const size_t keyframes = map.keyframes.size();
  if (m_params.system.localizationOnly) {
    // Frames are located in the loaded map's coordinates: its metric frame, if it has one, applies from the first.
    m_metricFrame.setLoaded(fromMapMetricFrame(map.metric));
  }
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    m_mapper->restoreMap(std::move(map.keyframes), std::move(map.edges));
    // Localisation-only searches the loaded keyframes; otherwise they stay out of the relocalisation index, which
    // holds the current segment's keyframes only (their coordinates are not the loaded map's).
    if (m_params.system.localizationOnly && !m_mapper->indexGlobalMap()) {
      throw vpHSlamException(vpHSlamException::unsupported,
                             path + ": system.localizationOnly needs a vocabulary (none found: set HSLAM_VOCABULARY)");
    }
  }
  m_localizationReady = m_params.system.localizationOnly;
  if (m_localizer) {
    m_localizer->reset(); // what it gathered came from the previous map
  }
  // New keyframes are numbered after the loaded ones: ids stay unique in the global map and in a saved map.
  m_keyframeCount = std::max(m_keyframeCount.load(), lastId + 1);
  m_recorder.setFirstKeyframeId(m_keyframeCount.load());
  VP_HSLAM_LOG(vpHSlamLog::info, "map loaded from " << path << ": " << keyframes << " keyframes");
}
} // namespace hslam
