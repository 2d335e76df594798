/*
 * H-SLAM for ViSP.
 */
// Relocalisation of a lost frame into the current map (SlamSystem, tracking thread), and the stored-map fixes that
// may seed an emptied window again; the check that a relocalised pose holds (the map's points, or the motion a
// moving camera kept). See SlamSystem.h.
#include "system/SlamSystem.h"

#include "system/LocalMapper.h"
#include "tracking/MotionContinuation.h"
#include "tracking/Relocalizer.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <cmath>

namespace hslam
{
bool SlamSystem::relocalizePose(const FramePtr &frame, CoarseMotionHistory &history, bool &described)
{
  ++m_relocAttempts;
  m_relocalizationEvidence.clear();
  m_hybrid->extract(frame->raw);
  RelocalizationFrame lost = m_hybrid->relocalizationFrame();
  described = !lost.descriptors.empty();
  if (!described) {
    // Nothing to match (covered lens, black frame): such frames do not count towards the relocalisation timeout,
    // which measures how long the camera saw something it could not place.
    m_lostSince = frame->timestamp;
    return false;
  }
  synchronize(); // nothing is queued while lost; this only waits for a job still running
  RelocalizationResult r = relocalizeByPlaceRecognition(frame, lost);
  recordStoredMapFix(frame, r);
  if (!r.success && m_windowRelocalization && m_params.tracking.relocalizeInWindow) {
    // The window's keyframes with ORB points triangulated between them (see WindowRelocalization.h).
    std::vector<WindowView> views;
    {
      std::lock_guard<std::mutex> lock(m_mapperMutex);
      views = m_mapper->windowViews();
    }
    const double t0 = nowMs();
    const RelocalizationKeyframe window = m_windowRelocalization->windowPoints(views);
    const double t1 = nowMs();
    const RelocalizationFrame described = m_windowRelocalization->describe(frame->raw);
    RelocalizerOptions windowOptions = WindowRelocalization::matchingOptions();
    windowOptions.minInliers = m_params.tracking.relocalizationMinInliers;
    r = relocalize(described, {&window}, m_preprocessor.intrinsics(), windowOptions);
    if (r.success) {
      // Only these matches may confirm the alignment later (SlamSystem::trackInitialized): the window's corners
      // are too few after a long cover. A bag-of-words relocalisation stays confirmed by the corners alone.
      m_relocalizationEvidence = r.inlierObservations;
    }
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": window relocalisation " << (r.success ? "found" : "no")
                                             << " pose, " << window.wX.size() << " triangulated points, "
                                             << described.uv.size() << " keypoints, " << r.matches << " matches, "
                                             << r.inliers << " inliers; " << t1 - t0 << " ms for the window's points, "
                                             << nowMs() - t1 << " ms for the frame");
  }
  if (!r.success) {
    return false;
  }
  // The joint optimisation against the current tracking reference refines (and checks) the pose.
  const SE3d wMref = m_recorder.keyframePose(m_trackerRefKeyframe);
  history.valid = true;
  history.lastMref = r.cTw * wMref;
  history.prelastMref = history.lastMref;
  history.lastAffine = m_lastAffine;
  return true;
}

RelocalizationResult SlamSystem::relocalizeByPlaceRecognition(const FramePtr &frame, RelocalizationFrame &features,
                                                              int preferred)
{
  std::vector<RelocalizationKeyframe> candidates;
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    candidates = m_mapper->relocalizationCandidates(features, m_params.tracking.relocalizationCandidates, preferred);
  }
  std::vector<const RelocalizationKeyframe *> pointers;
  for (const RelocalizationKeyframe &k : candidates) {
    pointers.push_back(&k);
  }
  RelocalizerOptions options;
  options.minInliers = m_params.tracking.relocalizationMinInliers;
  const RelocalizationResult r = relocalize(features, pointers, m_preprocessor.intrinsics(), options);
  // On failure: the most matches and inliers any candidate had.
  VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": relocalisation " << (r.success ? "found" : "no")
                                           << " pose, " << candidates.size() << " candidates, " << r.candidatesTried
                                           << " tried, keyframe " << r.keyframeId << ", " << r.matches << " matches, "
                                           << r.inliers << " inliers");
  return r;
}

bool SlamSystem::relocalizationConfirmed(const FramePtr &frame, bool aligned, const SE3d &cMwAligned,
                                         const CoarseTrackingResult &result, const char *attempt) const
{
  // Accepted only when the map's corners confirm it too (tracking.relocalizationCheckInliers, 15 by default): a lost
  // camera pointed at something new can be aligned photometrically to a wrong place (measured on 7-Scenes after
  // covers of 15 and 40 frames: "successful" alignments with 0-3 ORB inliers, one with a gain change of e^-1.4).
  // Right relocalisations after a 5-frame cover had 16-58 inliers; the former 20 (twice a tracked frame's) refused
  // four of five of them in slam mode with direct tracking (point budgets 480-520).
  // A relocalisation on the window's triangulated points is confirmed by its own matches too: the window's corners
  // are few, and after a long cover the camera often sees them from too far away to match 15 (7-Scenes, frames
  // 120-160 black: 4-8 corner inliers while 30-50 of those matches agreed with the aligned pose). The alignment's
  // own checks (residuals, outliers, brightness) must have passed, and it must have stayed within the matches'
  // 2.4 px (chi2, 2 dof, 95 %) of them.
  // Such a pose must also fit the reference photometrically. In a scene of repeated texture the window's points gave
  // PnP poses 8-17 degrees off (Tsukuba: 7 of 48 runs over 8 covers and 6 point budgets, 5 of them with source
  // frames 30-49 black and every 2nd frame fed), which the alignment kept with 22-41 of their 30-42 matches agreeing,
  // and the run went on in one segment at 7-61 cm ATE instead of 0.3-0.7 cm. Those alignments left 52-59 % of the
  // reference's residuals below the cutoff, the 47 right window relocalisations 71-92 % (9 covers of 7-Scenes and
  // Tsukuba, 6 budgets). tracking.relocalizationMinInlierRatio sits between the two; a refused frame is lost and the
  // next one tries again (the camera's motion continued is not subject to it: KITTI's right ones left 46-80 %).
  const int confirmedByRelocalization =
      aligned ? countReprojectionInliers(cMwAligned, m_relocalizationEvidence, m_preprocessor.intrinsics(),
                                         PoseOnlyOptions().chi2Threshold)
              : 0;
  VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": relocalisation check" << attempt << ": alignment "
                                           << (aligned ? "ok" : coarseTrackingStatusName(result.status))
                                           << " (inlier ratio " << result.inlierRatio << "), " << m_indirect.matches
                                           << " ORB matches, " << m_indirect.inliers << " inliers"
                                           << (m_indirect.recovered ? " (found without prediction)" : "") << ", "
                                           << confirmedByRelocalization << " of " << m_relocalizationEvidence.size()
                                           << " relocalisation matches agree");
  const int needed = m_params.tracking.relocalizationCheckInliers;
  const bool fitsPhotometrically =
      m_relocalizationEvidence.empty() || result.inlierRatio >= m_params.tracking.relocalizationMinInlierRatio;
  return aligned && fitsPhotometrically &&
         ((m_indirect.usable && m_indirect.inliers >= needed) || confirmedByRelocalization >= needed);
}

double SlamSystem::lostSteps(int frameId) const
{
  const int step = m_lastFrameId - m_prelastFrameId;
  if (m_lastFrameId < 0 || m_prelastFrameId < 0 || step <= 0) {
    return 0.;
  }
  return static_cast<double>(frameId - m_lastFrameId) / step;
}

void SlamSystem::recordStoredMapFix(const FramePtr &frame, const RelocalizationResult &r)
{
  if (!r.success) {
    m_storedMapFix = StoredMapFix();
    return;
  }
  StoredMapFix fix;
  fix.frameId = frame->id;
  fix.cMw = r.cTw;
  fix.keyframeId = r.keyframeId;
  const StoredMapFix &previous = m_storedMapFix;
  if (previous.frameId >= 0 && previous.frameId + 1 == frame->id) {
    const FixAgreement a = compareFixes(previous.cMw, fix.cMw, medianInlierDepth(r));
    fix.agreesWithPrevious = a.agrees;
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame->id << ": stored-map fix " << a.angleDeg << " deg and "
                                             << a.depthShare << " scene depths from the previous frame's"
                                             << (a.agrees ? " (agrees)" : ""));
  }
  m_storedMapFix = fix;
}
} // namespace hslam
