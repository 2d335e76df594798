/*
 * H-SLAM for ViSP.
 */
#include "tracking/TrackingStateMachine.h"

#include "tracking/MotionContinuation.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <cmath>

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
} // namespace

TrackingStateMachine::Phase TrackingStateMachine::next(Phase from, Event event)
{
  switch (event) {
  case Event::initialized:
    return from == Phase::newSegment ? Phase::tracking : from;
  case Event::aligned:
  case Event::failed:
  case Event::refused:
    return from; // tracking, continuedMotion (the relocalised frame), relocalizing: unchanged
  case Event::failedTooOften:
    return from == Phase::tracking ? Phase::relocalizing : from;
  case Event::failedForGood:
    return from == Phase::tracking || from == Phase::continuedMotion ? Phase::lost : from;
  case Event::noReference:
    return from == Phase::newSegment ? from : Phase::lost;
  case Event::timedOut:
    return from == Phase::relocalizing ? Phase::lost : from;
  case Event::relocalized:
    return from == Phase::relocalizing ? Phase::tracking : from;
  case Event::relocalizedMoving:
    return from == Phase::relocalizing ? Phase::continuedMotion : from;
  case Event::motionUsed:
    return from == Phase::continuedMotion ? Phase::tracking : from;
  case Event::segmentEnded:
    return Phase::newSegment;
  }
  return from;
}

TrackingStateMachine::TrackingStateMachine(const vpHSlamParameters &params, FrameTracker &frames,
                                           LostFrameRelocalizer *relocalizer, TrackingMap &map, bool seedFromStoredMap,
                                           bool relocalization)
    : m_params(params), m_frames(frames), m_relocalizer(relocalizer), m_map(map),
      m_seedFromStoredMap(seedFromStoredMap), m_relocalization(relocalization && relocalizer != nullptr)
{
}

void TrackingStateMachine::startSegment(int lastFrameId, int prelastFrameId)
{
  transition(Event::initialized);
  m_lastFrameId = lastFrameId;
  m_prelastFrameId = prelastFrameId;
  m_consecutiveFailures = 0;
}

void TrackingStateMachine::endSegment()
{
  transition(Event::segmentEnded);
  m_forcedKeyframes = 0;
  if (m_relocalizer) {
    m_relocalizer->forgetWindow(); // the window goes with the segment
    m_relocalizer->forgetStoredMapFix();
  }
  m_continuedMotion.reset();
  m_lastFrameId = m_prelastFrameId = -1;
  m_consecutiveFailures = 0;
}

TrackingStateMachine::Outcome TrackingStateMachine::track(const FramePtr &frame)
{
  Outcome out;
  if (!m_frames.hasReference()) {
    transition(Event::noReference);
    out.report = Outcome::endSegment;
    return out;
  }
  const SE3d wMref = m_map.keyframePose(m_frames.referenceKeyframe());
  Start start;
  start.history = motionHistory(wMref);
  const bool relocalizing = m_phase == Phase::relocalizing;
  if (relocalizing) {
    if (frame->timestamp - m_lostSince > m_params.tracking.relocalizationTimeout) {
      VP_HSLAM_LOG(vpHSlamLog::warning, "frame " << frame->id << ": relocalisation failed for "
                                                 << frame->timestamp - m_lostSince
                                                 << " s; a new map segment will be initialised");
      transition(Event::timedOut);
      out.report = Outcome::endSegment;
      return out;
    }
    out.relocalizationAttempted = true;
    relocalize(frame, start);
  }
  Alignment a;
  a.success = m_frames.estimatePose(frame, start.history, relocalizing, a.newMref, a.affine, a.result);
  const bool seeded = relocalizing && seedsFromStoredMap(*frame, a);
  if (seeded) {
    a.newMref = m_relocalizer->storedMapFix().cMw * wMref;
    a.affine = m_frames.lastAffine();
    a.success = true;
  }
  if (relocalizing && !seeded && !relocalizationConfirmed(frame, wMref, start, a)) {
    transition(Event::refused);
    out.report = Outcome::lost; // the relocalised pose did not hold against the map: try the next frame
    return out;
  }
  if (relocalizing) {
    finishRelocalization(*frame, start, a, seeded);
  }
  Outcome tracked = conclude(frame, wMref, a, relocalizing, seeded);
  tracked.relocalizationAttempted = out.relocalizationAttempted;
  return tracked;
}

CoarseMotionHistory TrackingStateMachine::motionHistory(const SE3d &wMref)
{
  // Motion history from the recorded poses (DSO: from the frame shells, under the pose lock).
  CoarseMotionHistory history;
  SE3d wMlast, wMprelast;
  if (m_lastFrameId >= 0 && m_prelastFrameId >= 0 && m_map.framePose(m_lastFrameId, wMlast) &&
      m_map.framePose(m_prelastFrameId, wMprelast)) {
    history.valid = true;
    history.lastMref = wMlast.inverse() * wMref;
    history.prelastMref = wMprelast.inverse() * wMref;
  } else if (m_lastFrameId >= 0 && m_map.framePose(m_lastFrameId, wMlast)) {
    // One frame only: no velocity yet; start from the last pose (DSO tries identity from the reference). After a
    // relocalisation where the motion continued, that motion (KITTI 06, frames 20-24 black, budget 510: from no
    // motion the next two frames were placed 12 and 30 px on instead of about 60, and the run ended at 0.25 m).
    history.valid = true;
    history.lastMref = wMlast.inverse() * wMref;
    history.prelastMref = m_continuedMotion ? m_continuedMotion->inverse() * history.lastMref : history.lastMref;
  }
  m_continuedMotion.reset();
  transition(Event::motionUsed);
  history.lastAffine = m_frames.lastAffine();
  return history;
}

void TrackingStateMachine::relocalize(const FramePtr &frame, Start &start)
{
  bool described = false;
  start.beforeLoss = start.history;
  const bool found =
      m_relocalizer->relocalize(frame, m_frames.referenceKeyframe(), m_frames.lastAffine(), start.history, described);
  if (!described) {
    // Nothing to match (covered lens, black frame): such frames do not count towards the relocalisation timeout,
    // which measures how long the camera saw something it could not place.
    m_lostSince = frame->timestamp;
  }
  if (!found && start.history.valid) {
    // No place recognised: after a short loss the camera is often still near its last pose, where the hybrid
    // step (guided matching, then matching without a prediction and PnP against the window's corners) and the
    // joint alignment can find it; the same checks as any frame decide. Measured on 7-Scenes with frames
    // 120-125 black, fast preset: BoW candidates gave at most 15 matches, this found the camera at once.
    // A camera on a vehicle kept moving instead: tried second (relocalizationConfirmed()).
    start.continued = described ? continueMotion(start.history, lostSteps(frame->id)) : CoarseMotionHistory();
    start.history.prelastMref = start.history.lastMref;
  }
}

bool TrackingStateMachine::seedsFromStoredMap(const Frame &frame, const Alignment &a) const
{
  // The window cannot hold the relocalised pose when it has (almost) no point left: a turn in place made keyframes
  // that triangulated nothing (3-lap synthetic loop: 198, 73, 29, then 0 window points, while bag-of-words + PnP
  // placed every lost frame in the stored map with 73-144 inliers). Two consecutive fixes that agree are then taken
  // as they are, and the frame becomes a keyframe: the stored points it sees are re-activated in it (early
  // adoption, LocalMapper::reuseGlobalPoints) and the window has points again.
  const LostFrameRelocalizer::StoredMapFix &fix = m_relocalizer->storedMapFix();
  return !a.success && fix.frameId == frame.id && fix.agreesWithPrevious && m_seedFromStoredMap &&
         (a.result.status == CoarseTrackingStatus::noReference ||
          a.result.status == CoarseTrackingStatus::tooFewResiduals);
}

bool TrackingStateMachine::relocalizationConfirmed(const FramePtr &frame, const SE3d &wMref, const Start &start,
                                                   Alignment &a)
{
  bool confirmed =
      m_relocalizer->confirmed(*frame, a.success, a.newMref * wMref.inverse(), a.result, m_frames.indirect(), "");
  if ((!a.success || !confirmed) && start.continued.valid) {
    a.success = m_frames.estimatePose(frame, start.continued, true, a.newMref, a.affine, a.result);
    confirmed = m_relocalizer->confirmed(*frame, a.success, a.newMref * wMref.inverse(), a.result, m_frames.indirect(),
                                         " (motion continued)");
    if (a.success && !confirmed) { // a failed alignment has not moved from the prediction: nothing to check
      const ContinuedMotionCheck check = checkContinuedMotion(start.continued, a.newMref);
      VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": alignment from the continued motion ended "
                                               << check.stepShare << " of a step and " << check.rotationDeg
                                               << " deg from it" << (check.kept ? ": the camera kept moving" : ""));
      if (check.kept) {
        confirmed = true;
        m_continuedMotion = start.continued.lastMref * start.continued.prelastMref.inverse();
        m_forcedKeyframes = kKeyframesAfterContinuedMotion;
      }
    }
  }
  return a.success && confirmed;
}

void TrackingStateMachine::finishRelocalization(const Frame &frame, const Start &start, const Alignment &a, bool seeded)
{
  if (!m_continuedMotion && start.beforeLoss.valid && a.success) {
    // Placed by the map's points where the camera's motion continued would have put it: the camera kept moving, and
    // the next frame starts from that motion too, not from none (KITTI 06, hybrid tracking, frames 35-39 black,
    // budget 505: the window's points placed the car right, the frame after was placed 0.4 m on instead of 1.2 m and
    // the run ended at 0.117 m; 0.028 m with the motion kept).
    const CoarseMotionHistory expected = continueMotion(start.beforeLoss, lostSteps(frame.id));
    if (expected.valid && checkContinuedMotion(expected, a.newMref).kept) {
      m_continuedMotion = expected.lastMref * expected.prelastMref.inverse();
    }
  }
  transition(m_continuedMotion ? Event::relocalizedMoving : Event::relocalized);
  m_relocalizer->forgetWindow(); // the window moves on: its described keyframes would go stale
  VP_HSLAM_LOG(vpHSlamLog::info, "frame " << frame.id << ": relocalised after " << frame.timestamp - m_lostSince
                                          << " s, tracking resumes in the same map"
                                          << (seeded ? "; the window is seeded from the stored map" : ""));
}

TrackingStateMachine::Outcome TrackingStateMachine::conclude(const FramePtr &frame, const SE3d &wMref,
                                                             const Alignment &a, bool relocalizedNow, bool seeded)
{
  Outcome out;
  out.relocalized = relocalizedNow;
  const bool finite = a.newMref.translation().allFinite() && a.newMref.unitQuaternion().coeffs().allFinite() &&
                      std::isfinite(a.affine.a) && std::isfinite(a.affine.b);
  if (!a.success) {
    ++m_consecutiveFailures;
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": direct alignment failed ("
                                             << coarseTrackingStatusName(a.result.status) << "), "
                                             << m_consecutiveFailures << " in a row");
  } else {
    m_consecutiveFailures = 0;
  }
  const bool tooMany = m_consecutiveFailures > m_params.system.maxTrackingFailures;
  if (finite && tooMany && m_relocalization && m_map.indexesKeyframes()) {
    // The map stays: lost frames try relocalisation into it (frames until then are reported lost).
    VP_HSLAM_LOG(vpHSlamLog::info, "frame " << frame->id << ": tracking lost ("
                                            << coarseTrackingStatusName(a.result.status) << "); relocalising");
    transition(Event::failedTooOften);
    m_lostSince = frame->timestamp;
    m_relocalizer->forgetStoredMapFix();
    m_continuedMotion.reset();
    m_consecutiveFailures = 0;
    out.report = Outcome::lost;
    return out;
  }
  if (!finite || tooMany) {
    VP_HSLAM_LOG(vpHSlamLog::warning, "frame " << frame->id << ": tracking lost ("
                                               << coarseTrackingStatusName(a.result.status)
                                               << "); a new map segment will be initialised");
    transition(Event::failedForGood);
    out.report = Outcome::endSegment;
    return out;
  }
  transition(a.success ? Event::aligned : Event::failed);
  frame->affine = a.affine;
  frame->cMw = a.newMref * wMref.inverse();
  out.refMc = a.newMref.inverse();
  m_frames.setLastAffine(a.affine);
  // After a relocalisation the last tracked frame is from before the loss: no velocity to extrapolate from it
  // (measured on 7-Scenes with frames 120-135 black: the jump across the loss taken as one frame's motion sent the
  // next frames' predictions tens of pixels off and the window collapsed within 8 frames).
  m_prelastFrameId = relocalizedNow ? -1 : m_lastFrameId;
  m_lastFrameId = frame->id;
  // A failed alignment keeps the predicted pose (DSO) but neither makes a keyframe nor feeds mapping.
  if (seeded) {
    out.needKeyframe = true;
    m_frames.noteKeyframeRequested(); // as keyframeNeeded() does for a keyframe it asks for
  } else if (a.success) {
    const bool forced = m_forcedKeyframes > 0;
    m_forcedKeyframes -= forced ? 1 : 0;
    out.needKeyframe = m_frames.keyframeNeeded(frame, a.result, forced);
  }
  out.report = Outcome::tracked;
  out.aligned = a.success;
  out.seedKeyframe = seeded ? m_relocalizer->storedMapFix().keyframeId : -1;
  return out;
}

double TrackingStateMachine::lostSteps(int frameId) const
{
  const int step = m_lastFrameId - m_prelastFrameId;
  if (m_lastFrameId < 0 || m_prelastFrameId < 0 || step <= 0) {
    return 0.;
  }
  return static_cast<double>(frameId - m_lastFrameId) / step;
}
} // namespace hslam
