/*
 * H-SLAM for ViSP.
 */
#include "system/SlamSystem.h"

#include "mapping/TwoViewInitializer.h"
#include "system/LocalMapper.h"
#include "tracking/MotionContinuation.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace hslam
{
namespace
{
/*!
  After a relocalisation where the camera kept moving (a vehicle found again by its continued motion), the relocalised
  frame and the next two become keyframes. The window's keyframes are then metres behind, the points it can still
  track are distant, and the flow-based keyframe rule waited up to 9 frames: KITTI 06 with frames 30-39 black drifted
  to 0.12 and 0.69 m ATE in 2 of 6 point budgets (0.02-0.04 m with these keyframes; 7 covers x 6 budgets: none above
  0.04 m). Not after other relocalisations: a hand-held camera comes back near the window, and the same keyframes
  pushed good ones out of it (7-Scenes, frames 120-160 black: 0.050-0.157 m instead of 0.037-0.089 m).
*/
constexpr int kKeyframesAfterContinuedMotion = 3;

//! DSO's keyframe flow weights are expressed for a 640 x 480 image: (640 + 480) pixels.
constexpr double kDsoReferenceWidthPlusHeight = 640. + 480.;

std::string where(int line)
{
  return std::string(__FILE__) + ":" + std::to_string(line) + ": ";
}
} // namespace

SlamSystem::SlamSystem(const vpHSlamCamera &camera, const vpHSlamParameters &parameters,
                       const vpHSlamPhotometricCalibration &photometric)
    : m_params(parameters),
      m_preprocessor(camera, photometric, parameters.system.usePhotometricCalibration, parameters.tracker)
{
  m_params.validate();
  const bool calibrated = m_preprocessor.usesPhotometricCalibration();
  OrbExtractorOptions orbOptions;
  orbOptions.maxFeatures = m_params.initializer.orbFeatures;
  m_initializer = std::make_unique<TwoViewInitializer>(m_params.initializer, m_preprocessor.intrinsics(), orbOptions);
  m_tracker = std::make_unique<CoarseTracker>(m_params.tracker, calibrated);
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
  m_mapper = std::make_unique<LocalMapper>(m_params, m_preprocessor.intrinsics(), m_preprocessor.width(),
                                           m_preprocessor.height(), calibrated,
                                           m_vocabulary ? &m_vocabulary->impl() : nullptr);
  // The frame's ORB features: hybrid / indirect tracking, localisation-only, and relocalisation with direct tracking
  // (frames are then described only while the camera is lost).
  if (!direct || m_params.system.localizationOnly || relocalizes) {
    m_hybrid = std::make_unique<HybridTracker>(m_params, m_preprocessor.intrinsics(), m_preprocessor.width(),
                                               m_preprocessor.height());
    m_windowRelocalization = std::make_unique<WindowRelocalization>(m_preprocessor.intrinsics());
  }
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
    state = localizeInLoadedMap(frame);
    m_cpuTrack += threadCpuMs() - c1;
  } else if (!m_initialized) {
    state = initialize(frame, I, exposure);
    m_runStats.addInitializationMs(nowMs() - t0);
    m_cpuInitialize += threadCpuMs() - c1;
  } else {
    m_cpuLastJob = 0.;
    state = trackInitialized(frame); // records its own tracking time (mapping excluded)
    if (m_params.system.deterministic) {
      m_cpuTrack += threadCpuMs() - c1 - m_cpuLastJob;
    } else {
      m_cpuTrack += threadCpuMs() - c1;
    }
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

void SlamSystem::adoptPreparedReference()
{
  std::unique_lock<std::mutex> lock(m_referenceMutex, std::try_to_lock);
  if (!lock.owns_lock() || !m_preparedReady) {
    return; // the back end is preparing one: keep the current reference for this frame
  }
  m_preparedTracker->carryRecentRmseFrom(*m_tracker); // DSO's lastCoarseRMSE belongs to the system
  std::swap(m_tracker, m_preparedTracker);
  m_trackerRefKeyframe = m_preparedRefKeyframe;
  m_trackerRefAffine = m_preparedRefAffine;
  m_trackerRefExposure = m_preparedRefExposure;
  m_preparedReady = false;
}

vpHSlam::State SlamSystem::trackInitialized(const FramePtr &frame)
{
  const double t0 = m_frameStartMs; // tracking time includes the preprocessing of the frame
  if (m_restartRequested.exchange(false)) {
    declareLost(true);
    return vpHSlam::stateInitializing; // the map is started again: not a loss of tracking
  }
  adoptPreparedReference();
  if (m_trackerRefKeyframe < 0) {
    declareLost();
    return vpHSlam::stateLost;
  }
  // Motion history from the recorded poses (DSO: from the frame shells, under the pose lock).
  CoarseMotionHistory history, continued, beforeLoss;
  SE3d wMref, wMlast, wMprelast;
  wMref = m_recorder.keyframePose(m_trackerRefKeyframe);
  if (m_lastFrameId >= 0 && m_prelastFrameId >= 0 && m_recorder.framePose(m_lastFrameId, wMlast) &&
      m_recorder.framePose(m_prelastFrameId, wMprelast)) {
    history.valid = true;
    history.lastMref = wMlast.inverse() * wMref;
    history.prelastMref = wMprelast.inverse() * wMref;
  } else if (m_lastFrameId >= 0 && m_recorder.framePose(m_lastFrameId, wMlast)) {
    // One frame only: no velocity yet; start from the last pose (DSO tries identity from the reference). After a
    // relocalisation where the motion continued, that motion (KITTI 06, frames 20-24 black, budget 510: from no
    // motion the next two frames were placed 12 and 30 px on instead of about 60, and the run ended at 0.25 m).
    history.valid = true;
    history.lastMref = wMlast.inverse() * wMref;
    history.prelastMref = m_continuedMotion ? m_continuedMotion->inverse() * history.lastMref : history.lastMref;
  }
  m_continuedMotion.reset();
  history.lastAffine = m_lastAffine;

  if (m_relocalizing) {
    if (frame->timestamp - m_lostSince > m_params.tracking.relocalizationTimeout) {
      VP_HSLAM_LOG(vpHSlamLog::warning, "frame " << frame->id << ": relocalisation failed for "
                                                 << frame->timestamp - m_lostSince
                                                 << " s; a new map segment will be initialised");
      declareLost();
      m_runStats.addTrackingMs(nowMs() - t0);
      return vpHSlam::stateLost;
    }
    bool described = false;
    beforeLoss = history;
    if (!relocalizePose(frame, history, described) && history.valid) {
      // No place recognised: after a short loss the camera is often still near its last pose, where the hybrid
      // step (guided matching, then matching without a prediction and PnP against the window's corners) and the
      // joint alignment can find it; the same checks as any frame decide. Measured on 7-Scenes with frames
      // 120-125 black, fast preset: BoW candidates gave at most 15 matches, this found the camera at once.
      // A camera on a vehicle kept moving instead: tried second, below.
      continued = described ? continueMotion(history, lostSteps(frame->id)) : CoarseMotionHistory();
      history.prelastMref = history.lastMref;
    }
  }
  SE3d newMref;
  AffineBrightness affine;
  CoarseTrackingResult result;
  bool success = estimatePose(frame, history, newMref, affine, result);
  const bool relocalizedNow = m_relocalizing;
  // The window cannot hold the relocalised pose when it has (almost) no point left: a turn in place made keyframes
  // that triangulated nothing (3-lap synthetic loop: 198, 73, 29, then 0 window points, while bag-of-words + PnP
  // placed every lost frame in the stored map with 73-144 inliers). Two consecutive fixes that agree are then taken
  // as they are, and the frame becomes a keyframe: the stored points it sees are re-activated in it (early
  // adoption, LocalMapper::reuseGlobalPoints) and the window has points again.
  const bool seedFromStoredMap =
      m_relocalizing && !success && m_storedMapFix.frameId == frame->id && m_storedMapFix.agreesWithPrevious &&
      m_params.tracking.seedFromStoredMap && m_mapper->keepsGlobalMap() && m_params.globalMap.reuse &&
      (result.status == CoarseTrackingStatus::noReference || result.status == CoarseTrackingStatus::tooFewResiduals);
  if (seedFromStoredMap) {
    newMref = m_storedMapFix.cMw * wMref;
    affine = m_lastAffine;
    success = true;
  }
  if (m_relocalizing && !seedFromStoredMap) {
    bool confirmed = relocalizationConfirmed(frame, success, newMref * wMref.inverse(), result, "");
    if ((!success || !confirmed) && continued.valid) {
      success = estimatePose(frame, continued, newMref, affine, result);
      confirmed = relocalizationConfirmed(frame, success, newMref * wMref.inverse(), result, " (motion continued)");
      if (success && !confirmed) { // a failed alignment has not moved from the prediction: nothing to check
        const ContinuedMotionCheck check = checkContinuedMotion(continued, newMref);
        VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": alignment from the continued motion ended "
                                                 << check.stepShare << " of a step and " << check.rotationDeg
                                                 << " deg from it" << (check.kept ? ": the camera kept moving" : ""));
        if (check.kept) {
          confirmed = true;
          m_continuedMotion = continued.lastMref * continued.prelastMref.inverse();
          m_forcedKeyframes = kKeyframesAfterContinuedMotion;
        }
      }
    }
    if (!success || !confirmed) {
      m_runStats.addTrackingMs(nowMs() - t0);
      return vpHSlam::stateLost; // the relocalised pose did not hold against the map: try the next frame
    }
  }
  if (m_relocalizing && !m_continuedMotion && beforeLoss.valid && success) {
    // Placed by the map's points where the camera's motion continued would have put it: the camera kept moving, and
    // the next frame starts from that motion too, not from none (KITTI 06, hybrid tracking, frames 35-39 black,
    // budget 505: the window's points placed the car right, the frame after was placed 0.4 m on instead of 1.2 m and
    // the run ended at 0.117 m; 0.028 m with the motion kept).
    const CoarseMotionHistory expected = continueMotion(beforeLoss, lostSteps(frame->id));
    if (expected.valid && checkContinuedMotion(expected, newMref).kept) {
      m_continuedMotion = expected.lastMref * expected.prelastMref.inverse();
    }
  }
  if (m_relocalizing) {
    m_relocalizing = false;
    if (m_windowRelocalization) {
      m_windowRelocalization->clear(); // the window moves on: its described keyframes would go stale
    }
    ++m_relocSuccesses;
    VP_HSLAM_LOG(vpHSlamLog::info, "frame " << frame->id << ": relocalised after " << frame->timestamp - m_lostSince
                                            << " s, tracking resumes in the same map"
                                            << (seedFromStoredMap ? "; the window is seeded from the stored map" : ""));
  }
  const bool finite = newMref.translation().allFinite() && newMref.unitQuaternion().coeffs().allFinite() &&
                      std::isfinite(affine.a) && std::isfinite(affine.b);
  if (!success) {
    ++m_consecutiveFailures;
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": direct alignment failed ("
                                             << coarseTrackingStatusName(result.status) << "), "
                                             << m_consecutiveFailures << " in a row");
  } else {
    m_consecutiveFailures = 0;
  }
  if (finite && m_consecutiveFailures > m_params.system.maxTrackingFailures && m_vocabulary && m_hybrid &&
      m_params.tracking.relocalize && m_mapper->indexesKeyframes()) {
    // The map stays: lost frames try relocalisation into it (frames until then are reported lost).
    m_runStats.addTrackingMs(nowMs() - t0);
    VP_HSLAM_LOG(vpHSlamLog::info, "frame " << frame->id << ": tracking lost ("
                                            << coarseTrackingStatusName(result.status) << "); relocalising");
    m_relocalizing = true;
    m_lostSince = frame->timestamp;
    m_storedMapFix = StoredMapFix();
    m_continuedMotion.reset();
    m_consecutiveFailures = 0;
    return vpHSlam::stateLost;
  }
  if (!finite || m_consecutiveFailures > m_params.system.maxTrackingFailures) {
    m_runStats.addTrackingMs(nowMs() - t0);
    VP_HSLAM_LOG(vpHSlamLog::warning, "frame " << frame->id << ": tracking lost ("
                                               << coarseTrackingStatusName(result.status)
                                               << "); a new map segment will be initialised");
    declareLost();
    return vpHSlam::stateLost;
  }
  frame->affine = affine;
  frame->cMw = newMref * wMref.inverse();
  const SE3d refMc = newMref.inverse();
  m_recorder.addFrame(frame->id, frame->timestamp, m_trackerRefKeyframe, refMc, m_segment);
  m_lastAffine = affine;
  // After a relocalisation the last tracked frame is from before the loss: no velocity to extrapolate from it
  // (measured on 7-Scenes with frames 120-135 black: the jump across the loss taken as one frame's motion sent the
  // next frames' predictions tens of pixels off and the window collapsed within 8 frames).
  m_prelastFrameId = relocalizedNow ? -1 : m_lastFrameId;
  m_lastFrameId = frame->id;

  // A failed alignment keeps the predicted pose (DSO) but neither makes a keyframe nor feeds mapping.
  const bool needKeyframe = seedFromStoredMap || (success && keyframeNeeded(frame, result));
  if (seedFromStoredMap) {
    m_framesSinceKeyframeRequest = 0; // as keyframeNeeded() does for a keyframe it asks for
  }
  m_runStats.addTrackingMs(nowMs() - t0);
  if (success) {
    MappingJob job;
    job.frame = frame;
    job.referenceKeyframe = m_trackerRefKeyframe;
    job.refMc = refMc;
    job.needKeyframe = needKeyframe;
    job.seedKeyframe = seedFromStoredMap ? m_storedMapFix.keyframeId : -1;
    job.relocalized = relocalizedNow;
    deliver(std::move(job));
  }
  return vpHSlam::stateTracking;
}

bool SlamSystem::estimatePose(const FramePtr &frame, CoarseMotionHistory history, SE3d &newMref,
                              AffineBrightness &affine, CoarseTrackingResult &result)
{
  if (!m_hybrid || (m_params.tracking.mode == vpHSlamParameters::trackingDirect && !m_relocalizing)) {
    return m_tracker->trackWithHypotheses(*frame, history, newMref, affine, result);
  }
  // Hybrid / indirect tracking, or a lost camera with direct tracking: the joint step, whose ORB inliers confirm a
  // relocalised pose.
  const bool indirectOnly = m_params.tracking.mode == vpHSlamParameters::trackingIndirect;
  m_hybrid->extract(frame->raw);
  m_hybrid->indirectStep(m_tracker->referenceFeatures(), CoarseTracker::predictConstantVelocity(history), m_indirect);
  bool success = false;
  if (m_indirect.usable) {
    m_indirect.term.poseFromGeometryOnly = indirectOnly;
    m_tracker->setGeometricTerm(&m_indirect.term);
    history.hasIndirectPose = true;
    history.indirectMref = m_indirect.newMref;
  }
  if (indirectOnly) {
    // The pose is the geometric one; the photometric side only estimates (a, b) and the keyframe criteria.
    newMref = m_indirect.newMref;
    affine = history.lastAffine;
    success = m_indirect.usable && m_tracker->track(*frame, newMref, affine, result);
    if (!m_indirect.usable) {
      result.status = CoarseTrackingStatus::tooFewResiduals;
    }
  } else {
    success = m_tracker->trackWithHypotheses(*frame, history, newMref, affine, result);
  }
  m_tracker->setGeometricTerm(nullptr);
  if (success) {
    m_runStats.addHybridFrame(m_indirect.matches, m_indirect.inliers, result.geometricWeight);
  }
  std::vector<vpImagePoint> matched;
  if (success && m_indirect.usable) {
    matched.reserve(m_indirect.term.uv.size());
    for (const Eigen::Vector2d &uv : m_indirect.term.uv) {
      matched.emplace_back(uv.y(), uv.x());
    }
  }
  std::lock_guard<std::mutex> lock(m_imageMutex);
  m_lastMatches.swap(matched);
  return success;
}

bool SlamSystem::keyframeNeeded(const FramePtr &frame, const CoarseTrackingResult &result)
{
  ++m_framesSinceKeyframeRequest;
  const vpHSlamParameters::Tracker &p = m_params.tracker;
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(m_trackerRefExposure, m_trackerRefAffine, frame->exposure, frame->affine, aji, bji);
  // DSO FullSystem::addActiveFrame: weighted optical flow + brightness change above 1, or the residual doubled.
  // DSO's flow weights are given per (w + h) of a 640x480 image (setting_maxShiftWeightT = 0.04 (640 + 480)) and
  // divided by the actual w + h, so the same share of the image diagonal triggers a keyframe at any size.
  const double sizeScale =
      kDsoReferenceWidthPlusHeight / static_cast<double>(m_preprocessor.width() + m_preprocessor.height());
  const double score =
      sizeScale * (p.maxShiftWeightT * std::sqrt(result.flowT) + p.maxShiftWeightR * std::sqrt(result.flowR) +
                   p.maxShiftWeightRT * std::sqrt(result.flowRT)) +
      p.maxAffineWeight * std::fabs(std::log(aji));
  const double firstRmse = m_tracker->firstRmse();
  bool need = score > 1. || (std::isfinite(firstRmse) && p.keyframeResidualFactor * firstRmse < result.rmse[0]);
  if (p.maxFramesBetweenKeyframes > 0 && m_framesSinceKeyframeRequest >= p.maxFramesBetweenKeyframes) {
    need = true;
  }
  if (m_forcedKeyframes > 0) {
    --m_forcedKeyframes;
    need = true;
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": flow T " << std::sqrt(result.flowT) << " RT "
                                           << std::sqrt(result.flowRT) << " px, log a_ji " << std::log(aji) << ", rmse "
                                           << result.rmse[0] << " (first " << firstRmse << "), keyframe score " << score
                                           << ", hypotheses " << result.hypothesesTried << ", iterations "
                                           << result.iterations << (need ? " -> keyframe" : ""));
  if (need) {
    m_framesSinceKeyframeRequest = 0;
  }
  return need;
}

void SlamSystem::dropPreparedReferenceAndSnapshot()
{
  {
    std::lock_guard<std::mutex> lock(m_referenceMutex);
    m_preparedReady = false;
  }
  {
    std::lock_guard<std::mutex> lock(m_snapshotMutex);
    m_snapshotPoints.clear();
    m_snapshotImmature = 0;
    m_snapshotMemoryMb = 0.;
    m_snapshotKeyframesHeld = 0;
  }
}

void SlamSystem::declareLost(bool discardSegment)
{
  // Keep the old segment (trajectory, keyframes) and chain the next one to the last known pose; a segment whose
  // initialisation proved wrong is discarded instead (DSO resets after a failed initialisation).
  synchronize();
  m_forcedKeyframes = 0;
  if (m_windowRelocalization) {
    m_windowRelocalization->clear(); // the window goes with the segment
  }
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
  m_trackerRefKeyframe = -1;
  m_initialized = false;
  m_relocalizing = false;
  m_storedMapFix = StoredMapFix();
  m_continuedMotion.reset();
  m_initializer->reset();
  m_initFirstFrame.reset();
  m_pendingFrames.clear();
  m_lastFrameId = m_prelastFrameId = -1;
  m_consecutiveFailures = 0;
  if (!discardSegment) {
    ++m_segment; // a discarded segment's number is used again
  }
}

void SlamSystem::reset()
{
  synchronize();
  if (m_windowRelocalization) {
    m_windowRelocalization->clear(); // keyframe ids start again: features kept by id would belong to other images
  }
  {
    std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
    m_mapper->reset(); // the global map too: a reset system starts from nothing (keyframe ids start again at 0)
  }
  dropPreparedReferenceAndSnapshot();
  m_recorder.clear();
  m_runStats.clear();
  m_initializer->reset();
  m_initFirstFrame.reset();
  m_pendingFrames.clear();
  m_trackerRefKeyframe = -1;
  m_initialized = false;
  m_segment = 0;
  m_segmentOrigin = SE3d();
  m_lastFrameId = m_prelastFrameId = -1;
  m_nextFrameId = 0;
  m_lastTimestamp = 0.;
  m_consecutiveFailures = 0;
  m_framesSinceKeyframeRequest = 0;
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
  m_relocalizing = false;
  m_storedMapFix = StoredMapFix();
  m_continuedMotion.reset();
  m_relocAttempts = 0;
  m_relocSuccesses = 0;
  m_localizationReady = false; // the loaded map went with the rest
  m_localizedKeyframe = -1;
  m_localMapKeyframe = -1;
  std::lock_guard<std::mutex> lock(m_imageMutex);
  m_lastImage.resize(0, 0);
}

} // namespace hslam
