/*
 * H-SLAM for ViSP.
 */
#include "tracking/LostFrameRelocalizer.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <chrono>

namespace hslam
{
namespace
{
//! Wall clock, milliseconds (debug timings only).
double wallMs()
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
} // namespace

RelocalizationResult recognizePlace(int frameId, RelocalizationFrame &features, TrackingMap &map,
                                    const vpHSlamParameters::Tracking &params, const PinholeIntrinsics &K,
                                    int preferred)
{
  const std::vector<RelocalizationKeyframe> candidates =
      map.relocalizationCandidates(features, params.relocalizationCandidates, preferred);
  std::vector<const RelocalizationKeyframe *> pointers;
  for (const RelocalizationKeyframe &k : candidates) {
    pointers.push_back(&k);
  }
  RelocalizerOptions options;
  options.minInliers = params.relocalizationMinInliers;
  const RelocalizationResult r = relocalize(features, pointers, K, options);
  // On failure: the most matches and inliers any candidate had.
  VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frameId << ": relocalisation " << (r.success ? "found" : "no")
                                           << " pose, " << candidates.size() << " candidates, " << r.candidatesTried
                                           << " tried, keyframe " << r.keyframeId << ", " << r.matches << " matches, "
                                           << r.inliers << " inliers");
  return r;
}

LostFrameRelocalizer::LostFrameRelocalizer(const vpHSlamParameters::Tracking &params, const PinholeIntrinsics &K,
                                           HybridTracker &hybrid, TrackingMap &map)
    : m_params(params), m_K(K), m_hybrid(hybrid), m_map(map), m_window(K)
{
}

bool LostFrameRelocalizer::relocalize(const FramePtr &frame, int referenceKeyframe, const AffineBrightness &lastAffine,
                                      CoarseMotionHistory &history, bool &described)
{
  m_evidence.clear();
  m_hybrid.extract(frame->raw);
  RelocalizationFrame lost = m_hybrid.relocalizationFrame();
  described = !lost.descriptors.empty();
  if (!described) {
    return false; // nothing to match (covered lens, black frame)
  }
  m_map.waitForMapping();
  RelocalizationResult r = recognizePlace(frame->id, lost, m_map, m_params, m_K);
  recordStoredMapFix(*frame, r);
  if (!r.success && m_params.relocalizeInWindow) {
    r = relocalizeInWindow(*frame);
  }
  if (!r.success) {
    return false;
  }
  // The joint optimisation against the current tracking reference refines (and checks) the pose.
  const SE3d wMref = m_map.keyframePose(referenceKeyframe);
  history.valid = true;
  history.lastMref = r.cTw * wMref;
  history.prelastMref = history.lastMref;
  history.lastAffine = lastAffine;
  return true;
}

RelocalizationResult LostFrameRelocalizer::relocalizeInWindow(const Frame &frame)
{
  // The window's keyframes with ORB points triangulated between them (see WindowRelocalization.h).
  const std::vector<WindowView> views = m_map.windowViews();
  const double t0 = wallMs();
  const RelocalizationKeyframe window = m_window.windowPoints(views);
  const double t1 = wallMs();
  const RelocalizationFrame described = m_window.describe(frame.raw);
  RelocalizerOptions windowOptions = WindowRelocalization::matchingOptions();
  windowOptions.minInliers = m_params.relocalizationMinInliers;
  RelocalizationResult r = hslam::relocalize(described, {&window}, m_K, windowOptions);
  if (r.success) {
    // Only these matches may confirm the alignment later (confirmed()): the window's corners are too few after a
    // long cover. A bag-of-words relocalisation stays confirmed by the corners alone.
    m_evidence = r.inlierObservations;
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame.id << ": window relocalisation " << (r.success ? "found" : "no")
                                           << " pose, " << window.wX.size() << " triangulated points, "
                                           << described.uv.size() << " keypoints, " << r.matches << " matches, "
                                           << r.inliers << " inliers; " << t1 - t0 << " ms for the window's points, "
                                           << wallMs() - t1 << " ms for the frame");
  return r;
}

bool LostFrameRelocalizer::confirmed(const Frame &frame, bool aligned, const SE3d &cMwAligned,
                                     const CoarseTrackingResult &result, const IndirectStepResult &indirect,
                                     const char *attempt) const
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
      aligned ? countReprojectionInliers(cMwAligned, m_evidence, m_K, PoseOnlyOptions().chi2Threshold) : 0;
  VP_HSLAM_LOG(vpHSlamLog::debug,
               "frame " << frame.id << ": relocalisation check" << attempt << ": alignment "
                        << (aligned ? "ok" : coarseTrackingStatusName(result.status)) << " (inlier ratio "
                        << result.inlierRatio << "), " << indirect.matches << " ORB matches, " << indirect.inliers
                        << " inliers" << (indirect.recovered ? " (found without prediction)" : "") << ", "
                        << confirmedByRelocalization << " of " << m_evidence.size() << " relocalisation matches agree");
  const int needed = m_params.relocalizationCheckInliers;
  const bool fitsPhotometrically = m_evidence.empty() || result.inlierRatio >= m_params.relocalizationMinInlierRatio;
  return aligned && fitsPhotometrically &&
         ((indirect.usable && indirect.inliers >= needed) || confirmedByRelocalization >= needed);
}

void LostFrameRelocalizer::recordStoredMapFix(const Frame &frame, const RelocalizationResult &r)
{
  if (!r.success) {
    m_storedMapFix = StoredMapFix();
    return;
  }
  StoredMapFix fix;
  fix.frameId = frame.id;
  fix.cMw = r.cTw;
  fix.keyframeId = r.keyframeId;
  const StoredMapFix &previous = m_storedMapFix;
  if (previous.frameId >= 0 && previous.frameId + 1 == frame.id) {
    const FixAgreement a = compareFixes(previous.cMw, fix.cMw, medianInlierDepth(r));
    fix.agreesWithPrevious = a.agrees;
    VP_HSLAM_LOG(vpHSlamLog::debug, "frame " << frame.id << ": stored-map fix " << a.angleDeg << " deg and "
                                             << a.depthShare << " scene depths from the previous frame's"
                                             << (a.agrees ? " (agrees)" : ""));
  }
  m_storedMapFix = fix;
}
} // namespace hslam
