/*
 * H-SLAM for ViSP.
 */
// Monocular initialisation (SlamSystem, tracking thread): two-view initialisation from ORB matches, the first map
// handed to the mapper, and the frames seen while initialising tracked backwards. See SlamSystem.h.
#include "system/SlamSystem.h"

#include "mapping/TwoViewInitializer.h"
#include "system/LocalMapper.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! Frames tracked backwards after initialisation need at least this share of inlier residuals (see the backfill).
constexpr double kMinBackfillInlierRatio = 0.75;
/*!
  ... and to see at least this share of the map points the first of them saw: with the view turning away from the map
  the alignment keeps a high inlier share on the few points left while its pose goes wrong (measured on the
  look-outward synthetic loop, initialised after turning: 25 % of the points left, pose errors up to 0.4 m, the
  trajectory's ATE 0.036 m instead of 0.010 m; on the shared real sequences the backfilled frames keep >= 98 %).
*/
constexpr double kMinBackfillOverlap = 0.5;
} // namespace

vpHSlam::State SlamSystem::initialize(const FramePtr &frame, const vpImage<unsigned char> &I, double exposure)
{
  const TwoViewInitializer::State initState = m_initializer->addFrame(frame->raw, frame->id);
  if (m_initializer->firstFrameId() == frame->id) {
    m_initFirstFrame = frame; // the initializer (re)started from this frame
  }
  if (initState != TwoViewInitializer::initialized) {
    const TwoViewAttempt &attempt = m_initializer->lastAttempt();
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": initialisation against frame "
                                             << m_initializer->firstFrameId() << ": outcome " << attempt.outcome << ", "
                                             << attempt.numMatches << " matches, " << attempt.numInliers
                                             << " inliers, flow " << attempt.medianFlowPx << " px, parallax "
                                             << attempt.parallaxDeg << " deg, R_H " << attempt.scoreRatioH);
    // Every frame without a pose is kept (raw, the newest maxFramesToInitialize), whatever the initializer's first
    // frame: after a restart of the initializer the older ones may still be tracked backwards later.
    PendingFrame pending;
    pending.I = I;
    pending.timestamp = frame->timestamp;
    pending.exposure = exposure;
    pending.id = frame->id;
    m_pendingFrames.push_back(std::move(pending));
    if (static_cast<int>(m_pendingFrames.size()) > m_params.initializer.maxFramesToInitialize) {
      m_pendingFrames.pop_front();
    }
    return vpHSlam::stateInitializing;
  }
  const TwoViewInitialization &init = m_initializer->result();
  if (!m_initFirstFrame || m_initFirstFrame->id != init.firstFrameId) {
    m_initializer->reset();
    return vpHSlam::stateInitializing;
  }
  // Nothing is queued for mapping while initialising: the back end is idle and may be driven from here.
  synchronize();
  std::lock_guard<std::mutex> mapperLock(m_mapperMutex);
  const int firstId = m_keyframeCount.load();
  if (!m_mapper->initialize(m_initFirstFrame, firstId, frame, firstId + 1, init, m_segmentOrigin)) {
    VP_HSLAM_LOG(vpHSlamLog::info, "initialisation from frames " << init.firstFrameId << " and " << frame->id
                                                                 << " gave too few points; trying again");
    m_mapper->clear();
    m_initializer->setFirstFrame(frame->raw, frame->id);
    m_initFirstFrame = frame;
    return vpHSlam::stateInitializing;
  }
  m_keyframeCount += 2;
  const SE3d wMfirst = m_initFirstFrame->cMw.inverse();
  const SE3d wMsecond = frame->cMw.inverse();
  m_recorder.addKeyframe(firstId, m_initFirstFrame->id, m_initFirstFrame->timestamp, wMfirst, m_segment);
  m_recorder.addKeyframe(firstId + 1, frame->id, frame->timestamp, wMsecond, m_segment);
  m_recorder.addFrame(m_initFirstFrame->id, m_initFirstFrame->timestamp, firstId, SE3d(), m_segment);
  m_recorder.addFrame(frame->id, frame->timestamp, firstId + 1, SE3d(), m_segment);
  if (m_initFirstFrame->id != frame->id) {
    ++m_trackedFrames; // the first frame got its pose now
  }
  VP_HSLAM_LOG(vpHSlamLog::info, "initialised from frames " << init.firstFrameId << " and " << frame->id << " ("
                                                            << init.points.size() << " points, parallax "
                                                            << init.parallaxDeg << " deg), segment " << m_segment);
  publishAfterKeyframe();
  adoptPreparedReference();
  backfillInitializationFrames(init.c2Mc1, init.firstFrameId, frame->id);
  m_initialized = true;
  m_initFirstFrame.reset();
  m_initializer->reset();
  m_lastAffine = frame->affine;
  // The frame before the second keyframe, when it has a pose (the first keyframe, or tracked backwards), gives the
  // next frame its velocity: starting from no motion, every third KITTI frame (3.6 m ahead) converged to a camera
  // that had hardly moved.
  SE3d wMbefore;
  m_prelastFrameId = m_recorder.framePose(frame->id - 1, wMbefore) ? frame->id - 1 : -1;
  m_lastFrameId = frame->id;
  m_consecutiveFailures = 0;
  m_framesSinceKeyframeRequest = 0;
  ++m_segmentsStarted;
  return vpHSlam::stateTracking;
}

void SlamSystem::backfillInitializationFrames(const SE3d &c2Mc1, int firstFrameId, int secondFrameId)
{
  // Tracked backwards from the second keyframe, each frame starting from its successor's pose moved by the mean
  // per-frame motion between the two keyframes (constant velocity backwards); past the first keyframe, whose pose
  // is known, on to the frames seen before the initializer's last restart. Stops at the first failure (older
  // frames are farther away).
  const int secondKeyframe = m_keyframeCount.load() - 1;
  const int steps = secondFrameId - firstFrameId;
  if (m_pendingFrames.empty() || steps < 1) {
    m_pendingFrames.clear();
    return;
  }
  if (!m_backfillTracker) {
    m_backfillTracker = std::make_unique<CoarseTracker>(m_params.tracker, m_preprocessor.usesPhotometricCalibration());
  }
  int referenceId = -1;
  AffineBrightness referenceAffine;
  double referenceExposure = 1.;
  if (!m_mapper->prepareTrackingReference(*m_backfillTracker, referenceId, referenceAffine, referenceExposure) ||
      referenceId != secondKeyframe) {
    m_pendingFrames.clear();
    return;
  }
  // Motion of one frame step backwards in time, expressed as previousMref -> thisMref = stepBack * previousMref.
  const SE3d c1Mc2 = c2Mc1.inverse();
  const SE3d stepBack = SE3d::exp(c1Mc2.log() / static_cast<double>(steps));
  CoarseMotionHistory history;
  history.valid = true;
  history.lastMref = SE3d();                // the second keyframe itself
  history.prelastMref = stepBack.inverse(); // a virtual frame one step after it
  history.lastAffine = referenceAffine;
  int filled = 0;
  int firstResiduals = 0; // residuals of the first frame filled (next to the second keyframe: the map in full view)
  bool crossedFirst = false;
  for (auto it = m_pendingFrames.rbegin(); it != m_pendingFrames.rend(); ++it) {
    if (it->id >= secondFrameId || it->id == firstFrameId) {
      continue;
    }
    if (it->id < firstFrameId && !crossedFirst) {
      // Crossing the first keyframe: its pose relative to the second keyframe is known exactly.
      history.prelastMref = history.lastMref;
      history.lastMref = c1Mc2;
      crossedFirst = true;
    }
    FramePtr frame = m_preprocessor.process(it->I, it->timestamp, it->exposure, it->id);
    SE3d newMref;
    AffineBrightness affine;
    CoarseTrackingResult result;
    // Going back in time the view drifts away from the map; a weakening inlier share marks where the alignment
    // stops being trustworthy (measured: >= 0.88 for correct poses on the shared sequences, 0.44-0.7 for the
    // drifting ones of KITTI started at frame 20).
    if (!m_backfillTracker->trackWithHypotheses(*frame, history, newMref, affine, result) ||
        result.inlierRatio < kMinBackfillInlierRatio ||
        (filled > 0 && result.residuals < kMinBackfillOverlap * firstResiduals)) {
      break;
    }
    if (filled == 0) {
      firstResiduals = result.residuals;
    }
    m_recorder.addFrame(frame->id, frame->timestamp, secondKeyframe, newMref.inverse(), m_segment);
    ++m_trackedFrames;
    ++filled;
    history.prelastMref = history.lastMref;
    history.lastMref = newMref;
    history.lastAffine = affine;
  }
  VP_HSLAM_LOG(vpHSlamLog::debug,
               "initialisation: " << filled << " of " << m_pendingFrames.size() << " earlier frames tracked backwards");
  m_pendingFrames.clear();
}
} // namespace hslam
