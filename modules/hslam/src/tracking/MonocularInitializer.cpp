/*
 * H-SLAM for ViSP.
 */
#include "tracking/MonocularInitializer.h"

#include <visp3/hslam/vpHSlamLog.h>

namespace hslam
{
namespace
{
//! Frames tracked backwards after initialisation need at least this share of inlier residuals (see backfill()).
constexpr double kMinBackfillInlierRatio = 0.75;
/*!
  ... and to see at least this share of the map points the first of them saw: with the view turning away from the map
  the alignment keeps a high inlier share on the few points left while its pose goes wrong (measured on the
  look-outward synthetic loop, initialised after turning: 25 % of the points left, pose errors up to 0.4 m, the
  trajectory's ATE 0.036 m instead of 0.010 m; on the shared real sequences the backfilled frames keep >= 98 %).
*/
constexpr double kMinBackfillOverlap = 0.5;
} // namespace

MonocularInitializer::MonocularInitializer(const vpHSlamParameters &params, const PinholeIntrinsics &K,
                                           bool photometricCalibration)
    : m_params(params), m_photometricCalibration(photometricCalibration),
      m_initializer(params.initializer, K, twoViewOrbOptions(params.initializer))
{
}

MonocularInitializer::~MonocularInitializer() = default;

bool MonocularInitializer::addFrame(const FramePtr &frame, const vpImage<unsigned char> &I, double exposure)
{
  const TwoViewInitializer::State state = m_initializer.addFrame(frame->raw, frame->id);
  if (m_initializer.firstFrameId() == frame->id) {
    m_firstFrame = frame; // the initializer (re)started from this frame
  }
  if (state != TwoViewInitializer::initialized) {
    const TwoViewAttempt &attempt = m_initializer.lastAttempt();
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": initialisation against frame "
                                             << m_initializer.firstFrameId() << ": outcome " << attempt.outcome << ", "
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
    m_pending.push_back(std::move(pending));
    if (static_cast<int>(m_pending.size()) > m_params.initializer.maxFramesToInitialize) {
      m_pending.pop_front();
    }
    return false;
  }
  if (!m_firstFrame || m_firstFrame->id != m_initializer.result().firstFrameId) {
    m_initializer.reset();
    return false;
  }
  return true;
}

void MonocularInitializer::restartFrom(const FramePtr &frame)
{
  m_initializer.setFirstFrame(frame->raw, frame->id);
  m_firstFrame = frame;
}

void MonocularInitializer::reset()
{
  m_initializer.reset();
  m_firstFrame.reset();
  m_pending.clear();
}

std::vector<MonocularInitializer::BackfilledFrame> MonocularInitializer::backfill(const SE3d &c2Mc1, int firstFrameId,
                                                                                  int secondFrameId,
                                                                                  const ReferenceSetter &setReference,
                                                                                  const Preprocess &preprocess)
{
  // Tracked backwards from the second keyframe, each frame starting from its successor's pose moved by the mean
  // per-frame motion between the two keyframes (constant velocity backwards); past the first keyframe, whose pose
  // is known, on to the frames seen before the initializer's last restart. Stops at the first failure (older
  // frames are farther away).
  std::vector<BackfilledFrame> filled;
  const int steps = secondFrameId - firstFrameId;
  if (m_pending.empty() || steps < 1) {
    m_pending.clear();
    return filled;
  }
  if (!m_backfillTracker) {
    m_backfillTracker = std::make_unique<CoarseTracker>(m_params.tracker, m_photometricCalibration);
  }
  AffineBrightness referenceAffine;
  if (!setReference(*m_backfillTracker, referenceAffine)) {
    m_pending.clear();
    return filled;
  }
  // Motion of one frame step backwards in time, expressed as previousMref -> thisMref = stepBack * previousMref.
  const SE3d c1Mc2 = c2Mc1.inverse();
  const SE3d stepBack = SE3d::exp(c1Mc2.log() / static_cast<double>(steps));
  CoarseMotionHistory history;
  history.valid = true;
  history.lastMref = SE3d();                // the second keyframe itself
  history.prelastMref = stepBack.inverse(); // a virtual frame one step after it
  history.lastAffine = referenceAffine;
  int firstResiduals = 0; // residuals of the first frame filled (next to the second keyframe: the map in full view)
  bool crossedFirst = false;
  for (auto it = m_pending.rbegin(); it != m_pending.rend(); ++it) {
    if (it->id >= secondFrameId || it->id == firstFrameId) {
      continue;
    }
    if (it->id < firstFrameId && !crossedFirst) {
      // Crossing the first keyframe: its pose relative to the second keyframe is known exactly.
      history.prelastMref = history.lastMref;
      history.lastMref = c1Mc2;
      crossedFirst = true;
    }
    FramePtr frame = preprocess(*it);
    SE3d newMref;
    AffineBrightness affine;
    CoarseTrackingResult result;
    // Going back in time the view drifts away from the map; a weakening inlier share marks where the alignment
    // stops being trustworthy (measured: >= 0.88 for correct poses on the shared sequences, 0.44-0.7 for the
    // drifting ones of KITTI started at frame 20).
    if (!m_backfillTracker->trackWithHypotheses(*frame, history, newMref, affine, result) ||
        result.inlierRatio < kMinBackfillInlierRatio ||
        (!filled.empty() && result.residuals < kMinBackfillOverlap * firstResiduals)) {
      break;
    }
    if (filled.empty()) {
      firstResiduals = result.residuals;
    }
    filled.push_back({frame->id, frame->timestamp, newMref.inverse()});
    history.prelastMref = history.lastMref;
    history.lastMref = newMref;
    history.lastAffine = affine;
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "initialisation: " << filled.size() << " of " << m_pending.size()
                                                     << " earlier frames tracked backwards");
  m_pending.clear();
  return filled;
}
} // namespace hslam
