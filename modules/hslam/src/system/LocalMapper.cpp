/*
 * H-SLAM for ViSP.
 */
#include "system/LocalMapper.h"

#include "mapping/TwoViewInitializer.h"
#include "system/RunStatistics.h"
#include "tracking/RelocalizationIndex.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <chrono>

namespace hslam
{
namespace
{
//! Raised while a loop correction runs (LocalMapper::correctingLoop(), read by the tracking thread).
struct CorrectingFlag {
  explicit CorrectingFlag(std::atomic<bool> &f) : flag(f) { flag = true; }
  ~CorrectingFlag() { flag = false; }
  std::atomic<bool> &flag;
};
} // namespace

LocalMapper::LocalMapper(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height,
                         bool photometricCalibration, const OrbVocabulary *vocabulary)
    : m_params(params), m_K0(K0), m_width(width), m_height(height), m_photometricCalibration(photometricCalibration),
      m_vocabulary(vocabulary), m_reference(K0, width, height), m_keeper(params, K0, width, height)
{
  makeSegmentComponents();
  if (vocabulary && params.system.mode == vpHSlamParameters::modeSlam) {
    m_loop = std::make_unique<LoopCloser>(params.loop, K0, *vocabulary);
    if (!params.system.deterministic) {
      m_loop->startThread(); // real time: detection and the pose graph off the mapping thread
    }
  }
}

LocalMapper::~LocalMapper() = default;

void LocalMapper::makeSegmentComponents()
{
  // Descriptor sharing: every selected point gets an ORB descriptor when tracking or the global map matches them.
  const bool withDescriptors = m_params.tracking.mode != vpHSlamParameters::trackingDirect ||
                               m_params.system.mode != vpHSlamParameters::modeVoStrict;
  m_window =
      std::make_unique<KeyframeWindow>(m_params, m_K0, m_width, m_height, m_photometricCalibration, withDescriptors);
  m_reference.clear();
  m_relocalization.reset();
  if (m_vocabulary) {
    m_relocalization = std::make_unique<RelocalizationIndex>(*m_vocabulary, m_K0);
  }
  m_marginalizedStates.clear();
}

void LocalMapper::clear()
{
  makeSegmentComponents();
  if (m_loop) {
    m_loop->clear(); // loops stay within a segment: the old one's features are of no further use
  }
  m_keeper.newSegment(); // the global map keeps what the old segment stored; re-use stays within a segment
  m_marginalizedCounted = false;
}

void LocalMapper::reset()
{
  clear();
  m_keeper.reset();
  if (m_loop) {
    m_loop->resetStatistics();
  }
}

// ------------------------------------------------------------------------------------------------ keyframes

bool LocalMapper::initialize(const FramePtr &first, int firstKeyframeId, const FramePtr &second, int secondKeyframeId,
                             const TwoViewInitialization &init, const SE3d &wMfirst)
{
  if (init.points.empty()) {
    return false;
  }
  if (!m_window->initialize(first, firstKeyframeId, second, secondKeyframeId, init, wMfirst)) {
    clear();
    return false;
  }
  // The second keyframe goes through the ordinary keyframe path from "optimise" on (nothing to trace yet).
  finishKeyframe(m_window->keyframes().back());
  m_window->addFirstKeyframeCorners();
  return true;
}

void LocalMapper::noteRelocalization()
{
  m_window->noteRelocalization();
}

void LocalMapper::makeNonKeyframe(const FramePtr &frame)
{
  m_window->trace(*frame);
}

void LocalMapper::makeKeyframe(const FramePtr &frame, int keyframeId, int seedKeyframe)
{
  const double t0 = threadCpuMs();
  collectGlobalBundleAdjustment(false); // its keyframes' states go out with this keyframe's
  if (seedKeyframe >= 0 && keepsGlobalMap()) {
    // The window could not hold the camera: the keyframe starts it again from the stored map. The old keyframes
    // leave first (into the global map): their few points, seen from a pose that drifted while they emptied,
    // dragged the new keyframe's pose in the window optimisation (3-lap synthetic loop: 3 points moved it 0.5 map
    // units away from where PnP had placed it, and no stored point matched there any more).
    while (!m_window->empty()) {
      marginalize(m_window->keyframes().front()->id());
    }
  }
  m_window->trace(*frame);
  const double t1 = threadCpuMs();
  const KeyframePtr kf = m_window->insertKeyframe(frame, keyframeId);
  const double t2 = threadCpuMs();
  finishKeyframe(kf, seedKeyframe);
  if (m_relocalization) {
    m_relocalization->addKeyframe(*kf);
  }
  closeLoops();
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << keyframeId << " timing: trace " << t1 - t0 << " ms, activation "
                                              << t2 - t1 << " ms, rest " << threadCpuMs() - t2 << " ms");
}

void LocalMapper::finishKeyframe(const KeyframePtr &kf, int seedKeyframe)
{
  const double t0 = threadCpuMs();
  const std::vector<int> toMarginalize = m_window->keyframesToMarginalize();
  m_window->optimize(*kf, m_keeper.globalMap(), toMarginalize, keepsGlobalMap());
  const double t1 = threadCpuMs();
  m_reference.build(m_window->keyframes());
  m_window->dropPointsOutOfView(*kf);
  m_window->makeNewImmaturePoints(*kf);
  if (keepsGlobalMap() && m_params.globalMap.reuse &&
      m_keeper.reuse(*kf, m_window->keyframes(), seedKeyframe, reuseRefinement()) > 0) {
    m_reference.build(m_window->keyframes()); // re-activated points are active in the newest keyframe: tracked at once
  }
  const double t2 = threadCpuMs();
  for (int id : toMarginalize) {
    marginalize(id);
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << kf->id() << " timing: optimisation " << t1 - t0
                                              << " ms, reference + selection " << t2 - t1 << " ms, marginalisation "
                                              << threadCpuMs() - t2 << " ms");
}

ReuseRefinement LocalMapper::reuseRefinement() const
{
  const KeyframeWindow &window = *m_window;
  ReuseRefinement r;
  r.refine = [&window](int hostId, const ImmaturePoint &pt, double idepth, double priorWeight) {
    const PointActivationResult a = window.refineNewPoint(hostId, pt, idepth, idepth, priorWeight);
    return ReuseRefinement::Result{a.accepted, a.idepth, a.idepthHessian};
  };
  r.activate = [](const ImmaturePoint &pt) { return PointActivation::makeMapPoint(pt); };
  return r;
}

void LocalMapper::marginalize(int id)
{
  const KeyframePtr kf = m_window->find(id);
  if (!kf) {
    return;
  }
  const std::vector<PairInformation> pairs =
      keepsGlobalMap() ? m_window->leavingPairs(id) : std::vector<PairInformation>();
  m_window->marginalize(id);
  if (m_relocalization) {
    m_relocalization->storeKeyframe(*kf);
  }
  KeyframeState state;
  state.id = id;
  state.wMc = kf->frame->cMw.inverse();
  state.inWindow = false;
  state.activePoints = 0;
  m_marginalizedStates.push_back(state);
  if (keepsGlobalMap()) {
    if (m_loop) {
      m_loop->handOver(*kf, m_keeper.segment(), m_window->keyframes()); // before storing: see below
    }
    // After storeKeyframe(): a keyframe culled at once leaves the relocalisation index and the loop closer whole.
    if (m_keeper.store(*kf, m_window->keyframes(), pairs)) {
      if (m_relocalization) {
        m_relocalization->removeKeyframe(id);
      }
      if (m_loop) {
        m_loop->removeKeyframe(id);
      }
    }
  }
  m_window->erase(id);
}

// ------------------------------------------------------------------------------------------------ loops

void LocalMapper::closeLoops()
{
  if (!m_loop) {
    return;
  }
  if (m_loop->threaded()) {
    // A correction the loop closer's thread solved since the last keyframe is applied first: the next query then
    // reads the corrected graph.
    applySolvedCorrections(false);
    m_loop->queueQuery(m_keeper.globalMap().graphCopy(), LoopCloser::connectedTo(m_window->keyframes()), windowPoses());
    return;
  }
  DetectedLoop loop;
  if (m_loop->detect(m_keeper.globalMap(), LoopCloser::connectedTo(m_window->keyframes()), loop)) {
    correctLoop(loop);
  }
}

bool LocalMapper::applySolvedCorrections(bool wait)
{
  bool applied = false;
  LoopCloser::Correction correction;
  while (m_loop && m_loop->threaded() && m_loop->takeCorrection(correction, wait)) {
    collectGlobalBundleAdjustment(false);
    applyCorrection(correction, std::chrono::steady_clock::now());
    applied = true;
  }
  return applied;
}

std::map<int, SE3d> LocalMapper::windowPoses() const
{
  std::map<int, SE3d> poses;
  for (const KeyframePtr &kf : m_window->keyframes()) {
    poses[kf->id()] = kf->frame->cMw;
  }
  return poses;
}

bool LocalMapper::correctLoop(const DetectedLoop &loop)
{
  LoopCloser::Correction correction;
  correction.loop = loop;
  return solveAndApply(correction);
}

void LocalMapper::setLandmarkSightings(LandmarkSightings landmarks)
{
  if (m_loop) {
    m_loop->setLandmarkSightings(std::move(landmarks));
  }
}

bool LocalMapper::correctLandmarks(int keyframe)
{
  if (!m_loop) {
    return false;
  }
  if (m_loop->threaded()) {
    m_loop->queueLandmarkCorrection(keyframe, m_keeper.globalMap().graphCopy(), windowPoses());
    return false;
  }
  LoopCloser::Correction correction;
  correction.loop.keyframe = keyframe;
  correction.landmark = true;
  return solveAndApply(correction);
}

bool LocalMapper::solveAndApply(LoopCloser::Correction &correction)
{
  // A global bundle adjustment of an earlier correction: written back if it has ended; else it goes on (it works on
  // its own copy) until this correction is known to succeed, and is stopped only then (its keyframes move; a new one
  // follows).
  collectGlobalBundleAdjustment(false);
  const auto t0 = std::chrono::steady_clock::now();
  {
    CorrectingFlag correcting(m_correctingLoop);
    if (!m_loop->solve(correction, m_keeper.globalMap(), windowPoses())) {
      return false;
    }
  }
  applyCorrection(correction, t0);
  return true;
}

void LocalMapper::applyCorrection(const LoopCloser::Correction &correction, std::chrono::steady_clock::time_point t0)
{
  CorrectingFlag correcting(m_correctingLoop);
  m_loop->cancelBackgroundJob(); // its result would undo this correction
  for (const auto &entry : correction.solution) {
    m_keeper.globalMap().applySimilarity(entry.first, entry.second);
    publishStoredKeyframe(entry.first, entry.second.scale());
  }
  const double ms =
      correction.solveMs + std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  m_loop->recordCorrectionApplied(ms, correction.landmark);
  if (correction.landmark) {
    VP_HSLAM_LOG(vpHSlamLog::info, "landmark seen again at keyframe " << correction.loop.keyframe << ": corrected, "
                                                                      << correction.solution.size()
                                                                      << " stored keyframes moved, " << ms << " ms");
  } else {
    VP_HSLAM_LOG(vpHSlamLog::info, "loop " << correction.loop.keyframe << "-" << correction.loop.candidate
                                           << " corrected, " << correction.solution.size()
                                           << " stored keyframes moved, " << ms << " ms");
  }
  startGlobalBundleAdjustment();
}

void LocalMapper::publishStoredKeyframe(int id, double scale)
{
  const GlobalKeyframe *g = m_keeper.globalMap().find(id);
  KeyframeState state;
  state.id = id;
  state.wMc = g->cMw.inverse();
  state.inWindow = false;
  state.scale = scale;
  m_marginalizedStates.push_back(state);
  if (m_relocalization) {
    m_relocalization->refreshKeyframe(*g);
  }
}

void LocalMapper::startGlobalBundleAdjustment()
{
  if (!m_params.loop.globalBundleAdjustment || !m_loop) {
    return;
  }
  std::unique_ptr<GlobalBundleJob> job =
      m_loop->makeGlobalBundleJob(m_keeper.globalMap(), m_keeper.segment(), windowPoses());
  if (m_params.system.deterministic) {
    job->run(); // in order, inside track(): the same output run to run
    finishGlobalBundleAdjustment(*job);
  } else {
    m_loop->runInBackground(std::move(job)); // a job of an earlier loop still running is cancelled
  }
}

bool LocalMapper::collectGlobalBundleAdjustment(bool wait)
{
  // Waiting: the loop closer's thread finishes its work first (its correction may start an adjustment).
  const bool corrected = wait && applySolvedCorrections(true);
  std::unique_ptr<GlobalBundleJob> job = m_loop ? m_loop->takeBackgroundJob(wait) : nullptr;
  if (!job) {
    return corrected;
  }
  finishGlobalBundleAdjustment(*job);
  return true;
}

void LocalMapper::finishGlobalBundleAdjustment(const GlobalBundleJob &job)
{
  const GlobalBundleSummary &s = job.summary;
  const std::vector<int> moved = applyGlobalBundleJob(job, m_keeper.globalMap());
  for (int id : moved) {
    publishStoredKeyframe(id, 1.);
  }
  m_loop->recordGlobalBundleAdjustment(s, !moved.empty());
  VP_HSLAM_LOG(vpHSlamLog::info, "global bundle adjustment "
                                     << (moved.empty() ? "failed" : "applied") << ": " << s.keyframes << " keyframes ("
                                     << moved.size() << " moved), " << s.points << " points, " << s.observations
                                     << " observations, " << s.iterations << " iterations, reprojection RMS "
                                     << s.rmsBeforePx << " -> " << s.rmsAfterPx << " px, " << s.seconds << " s");
}
} // namespace hslam
