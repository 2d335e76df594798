/*
 * H-SLAM for ViSP.
 */
#include "tracking/FrameTracker.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <cmath>

namespace hslam
{
namespace
{
//! DSO's keyframe flow weights are expressed for a 640 x 480 image: (640 + 480) pixels.
constexpr double kDsoReferenceWidthPlusHeight = 640. + 480.;
} // namespace

FrameTracker::FrameTracker(const vpHSlamParameters &params, bool photometricCalibration, int width, int height,
                           HybridTracker *hybrid)
    : m_params(params), m_width(width), m_height(height), m_hybrid(hybrid), m_adaptive(params.tracking, width),
      m_tracker(std::make_unique<CoarseTracker>(params.tracker, photometricCalibration))
{
}

void FrameTracker::adoptReference(std::unique_ptr<CoarseTracker> &prepared, int keyframeId,
                                  const AffineBrightness &affine, double exposure)
{
  prepared->carryRecentRmseFrom(*m_tracker); // DSO's lastCoarseRMSE belongs to the system
  std::swap(m_tracker, prepared);
  m_referenceKeyframe = keyframeId;
  m_referenceAffine = affine;
  m_referenceExposure = exposure;
}

bool FrameTracker::estimatePose(const FramePtr &frame, CoarseMotionHistory history, bool lost, SE3d &newMref,
                                AffineBrightness &affine, CoarseTrackingResult &result)
{
  const vpHSlamParameters::TrackingMode mode = m_params.tracking.mode;
  if (!m_hybrid || (mode == vpHSlamParameters::trackingDirect && !lost)) {
    m_lastReason = GeometricReason::none;
    return m_tracker->trackWithHypotheses(*frame, history, newMref, affine, result);
  }
  if (lost) {
    // A lost camera with direct or adaptive tracking: the joint step, whose ORB inliers confirm a relocalised pose.
    return estimateJoint(frame, history, GeometricReason::lost, newMref, affine, result);
  }
  if (mode == vpHSlamParameters::trackingAdaptive) {
    return estimateAdaptive(frame, history, newMref, affine, result);
  }
  return estimateJoint(frame, history, GeometricReason::always, newMref, affine, result);
}

bool FrameTracker::estimateAdaptive(const FramePtr &frame, const CoarseMotionHistory &history, SE3d &newMref,
                                    AffineBrightness &affine, CoarseTrackingResult &result)
{
  const SE3d predicted = CoarseTracker::predictConstantVelocity(history);
  const double shiftPx = history.valid ? m_tracker->meanShiftPx(history.lastMref, predicted) : 0.;
  GeometricReason reason = m_adaptive.beforeDirect(history.valid, shiftPx);
  if (reason != GeometricReason::none) {
    return estimateJoint(frame, history, reason, newMref, affine, result);
  }
  // The direct alignment first; its memory of the residuals is undone when its pose is not the one kept, so that the
  // joint step's hypotheses are bounded as they would have been.
  const CoarseTracker::RetrackState before = m_tracker->retrackState();
  SE3d directMref = newMref;
  AffineBrightness directAffine = affine;
  CoarseTrackingResult directResult;
  const bool direct = m_tracker->trackWithHypotheses(*frame, history, directMref, directAffine, directResult);
  const double measuredPx = direct && history.valid ? m_tracker->meanShiftPx(history.lastMref, directMref) : 0.;
  reason = m_adaptive.afterDirect(direct, directResult, measuredPx);
  VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": adaptive, predicted shift " << shiftPx << " px, direct "
                                           << (direct ? "ok" : "failed") << " after " << directResult.hypothesesTried
                                           << " hypotheses, shift " << measuredPx << " px -> "
                                           << geometricReasonName(reason));
  if (reason == GeometricReason::none) {
    m_lastReason = reason;
    newMref = directMref;
    affine = directAffine;
    result = directResult;
    publishMatches(false);
    return true;
  }
  const CoarseTracker::RetrackState afterDirect = m_tracker->retrackState();
  m_tracker->restoreRetrackState(before);
  if (estimateJoint(frame, history, reason, newMref, affine, result)) {
    return true;
  }
  if (!direct) {
    return false;
  }
  // The joint step failed where the direct alignment had succeeded (too few ORB inliers, say): the direct pose stands.
  m_tracker->restoreRetrackState(afterDirect);
  m_lastReason = GeometricReason::none;
  newMref = directMref;
  affine = directAffine;
  result = directResult;
  return true;
}

bool FrameTracker::estimateJoint(const FramePtr &frame, CoarseMotionHistory history, GeometricReason reason,
                                 SE3d &newMref, AffineBrightness &affine, CoarseTrackingResult &result)
{
  m_lastReason = reason;
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
    m_hybridSteps.push_back({m_indirect.matches, m_indirect.inliers, result.geometricWeight});
  }
  publishMatches(success && m_indirect.usable);
  return success;
}

void FrameTracker::publishMatches(bool success)
{
  std::vector<vpImagePoint> matched;
  if (success) {
    matched.reserve(m_indirect.term.uv.size());
    for (const Eigen::Vector2d &uv : m_indirect.term.uv) {
      matched.emplace_back(uv.y(), uv.x());
    }
  }
  std::lock_guard<std::mutex> lock(m_matchesMutex);
  m_lastMatches.swap(matched);
}

bool FrameTracker::keyframeNeeded(const FramePtr &frame, const CoarseTrackingResult &result, bool forced)
{
  ++m_framesSinceKeyframeRequest;
  const vpHSlamParameters::Tracker &p = m_params.tracker;
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(m_referenceExposure, m_referenceAffine, frame->exposure, frame->affine, aji, bji);
  // DSO FullSystem::addActiveFrame: weighted optical flow + brightness change above 1, or the residual doubled.
  // DSO's flow weights are given per (w + h) of a 640x480 image (setting_maxShiftWeightT = 0.04 (640 + 480)) and
  // divided by the actual w + h, so the same share of the image diagonal triggers a keyframe at any size.
  const double sizeScale = kDsoReferenceWidthPlusHeight / static_cast<double>(m_width + m_height);
  const double score =
      sizeScale * (p.maxShiftWeightT * std::sqrt(result.flowT) + p.maxShiftWeightR * std::sqrt(result.flowR) +
                   p.maxShiftWeightRT * std::sqrt(result.flowRT)) +
      p.maxAffineWeight * std::fabs(std::log(aji));
  const double firstRmse = m_tracker->firstRmse();
  bool need = score > 1. || (std::isfinite(firstRmse) && p.keyframeResidualFactor * firstRmse < result.rmse[0]);
  if (p.maxFramesBetweenKeyframes > 0 && m_framesSinceKeyframeRequest >= p.maxFramesBetweenKeyframes) {
    need = true;
  }
  if (forced) {
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

void FrameTracker::startSegment(const AffineBrightness &affine)
{
  m_lastAffine = affine;
  m_framesSinceKeyframeRequest = 0;
}

void FrameTracker::reset()
{
  m_referenceKeyframe = -1;
  m_framesSinceKeyframeRequest = 0;
}

std::vector<FrameTracker::HybridStep> FrameTracker::takeHybridSteps()
{
  std::vector<HybridStep> steps;
  steps.swap(m_hybridSteps);
  return steps;
}

std::vector<vpImagePoint> FrameTracker::descriptorMatches() const
{
  std::lock_guard<std::mutex> lock(m_matchesMutex);
  return m_lastMatches;
}
} // namespace hslam
