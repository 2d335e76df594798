/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopCloser.h"

#include "common/HeapBytes.h"
#include "features/OrbVocabulary.h"
#include "loop/LoopCorrection.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace hslam
{
namespace
{
//! Co-visible keyframes that widen the querying keyframe's side of a verification (its own view counts most).
constexpr size_t kQueryNeighbours = 2;
//! ... and the candidate's side (ORB-SLAM: the candidate's connected keyframes).
constexpr size_t kCandidateNeighbours = 4;

double msSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

LoopFeatureOptions featureOptions(const vpHSlamParameters::Loop &p)
{
  LoopFeatureOptions o;
  o.maxFeatures = p.featuresPerKeyframe;
  return o;
}
} // namespace

LoopCloser::LoopCloser(const vpHSlamParameters::Loop &params, const PinholeIntrinsics &K,
                       const OrbVocabulary &vocabulary)
    : m_params(params), m_K(K), m_vocabulary(vocabulary), m_extractor(featureOptions(params)),
      m_database(vocabulary.wordCount()), m_consistency(params.consistency)
{
}

LoopCloser::~LoopCloser()
{
  if (m_thread.joinable()) {
    {
      std::lock_guard<std::mutex> lock(m_queueMutex);
      m_stop = true;
    }
    m_wake.notify_all();
    m_thread.join();
  }
}

// ------------------------------------------------------------------------------------------------ the thread

void LoopCloser::startThread()
{
  if (!m_thread.joinable()) {
    m_thread = std::thread(&LoopCloser::run, this);
  }
}

void LoopCloser::run()
{
  for (;;) {
    Work work;
    {
      std::unique_lock<std::mutex> lock(m_queueMutex);
      m_wake.wait(lock, [this]() { return m_stop || !m_queue.empty(); });
      if (m_stop) {
        return;
      }
      work = std::move(m_queue.front());
      m_queue.pop_front();
      m_busy = true;
    }
    Correction correction;
    const bool solved = process(work, correction);
    {
      std::lock_guard<std::mutex> lock(m_queueMutex);
      if (solved) {
        m_corrections.push_back(std::move(correction));
        ++m_correctionsSolved;
      }
      m_published = m_stats;
      m_publishedBytes = heldBytes();
      m_busy = false;
    }
    m_idle.notify_all();
  }
}

bool LoopCloser::process(Work &work, Correction &correction)
{
  switch (work.kind) {
  case Work::handOver:
    addKeyframe(work.id, work.segment, work.image, work.samples);
    return false;
  case Work::remove:
    dropKeyframe(work.id);
    return false;
  case Work::newSightings:
    m_landmarks = std::move(work.landmarks);
    return false;
  case Work::query:
  case Work::landmarkCorrection:
    break;
  }
  int solved = 0;
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    solved = m_correctionsSolved;
  }
  // A copy made before the mapper applied every correction solved so far: its poses would undo them. A query's
  // keyframes stay pending for the next query; a landmark's correction is dropped (the next sighting asks again).
  if (work.correctionsApplied != solved) {
    return false;
  }
  correction.landmark = work.kind == Work::landmarkCorrection;
  if (correction.landmark) {
    correction.loop.keyframe = work.id;
  } else if (!detect(work.graph, work.connected, correction.loop)) {
    return false;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const bool ok = solve(correction, work.graph, work.windowPoses);
  correction.solveMs = msSince(t0);
  return ok;
}

void LoopCloser::enqueue(Work work)
{
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    m_queue.push_back(std::move(work));
  }
  m_wake.notify_one();
}

void LoopCloser::waitIdle(std::unique_lock<std::mutex> &lock)
{
  m_idle.wait(lock, [this]() { return m_queue.empty() && !m_busy; });
}

void LoopCloser::queueQuery(GlobalMap graph, std::set<int> connected, std::map<int, SE3d> windowPoses)
{
  Work work;
  work.kind = Work::query;
  work.graph = std::move(graph);
  work.connected = std::move(connected);
  work.windowPoses = std::move(windowPoses);
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    work.correctionsApplied = m_correctionsTaken;
  }
  enqueue(std::move(work));
}

bool LoopCloser::takeCorrection(Correction &correction, bool wait)
{
  std::unique_lock<std::mutex> lock(m_queueMutex);
  if (wait && m_thread.joinable()) {
    waitIdle(lock);
  }
  if (m_corrections.empty()) {
    return false;
  }
  correction = std::move(m_corrections.front());
  m_corrections.pop_front();
  ++m_correctionsTaken; // applied by the caller before it copies the map again
  return true;
}

// ------------------------------------------------------------------------------------------------ hand-over

void LoopCloser::addKeyframe(int id, int segment, const vpImage<unsigned char> &image,
                             const std::vector<IdepthSample> &samples)
{
  if (m_params.featuresPerKeyframe <= 0 || m_keyframes.count(id)) {
    return;
  }
  std::vector<OrbDescriptor> descriptors;
  Entry entry;
  entry.features = m_extractor.extract(id, image, samples, m_K, descriptors);
  entry.segment = segment;
  BowVector bow;
  m_vocabulary.transform(descriptors, bow);
  m_database.add(id, bow);
  m_keyframes.emplace(id, std::move(entry));
  if (segment != m_segment) {
    m_segment = segment;
    newSegment();
  }
  ++m_keyframesInSegment;
  m_pending.push_back(id);
}

bool LoopCloser::detect(const GlobalMap &map, const std::set<int> &connected, DetectedLoop &loop)
{
  std::vector<int> pending;
  pending.swap(m_pending);
  for (int id : pending) {
    if (m_keyframes.count(id) && map.find(id) && query(id, map, connected, loop)) {
      return true; // the later ones are not queried: their poses move with the correction
    }
  }
  return false;
}

bool LoopCloser::query(int id, const GlobalMap &map, const std::set<int> &connected, DetectedLoop &loop)
{
  if (m_keyframesInSegment - m_keyframeOfLastLoop < m_params.minKeyframesBetween) {
    return false;
  }
  BowVector bow;
  if (!m_database.vectorOf(id, bow)) {
    return false;
  }
  const auto t0 = std::chrono::steady_clock::now();
  ++m_stats.detections;
  const std::vector<int> neighbours = map.covisibleWith(id);
  const std::vector<double> scores = m_database.scoresWith(bow, neighbours);
  if (scores.empty()) { // nothing to say what "alike" means here
    m_stats.detectionMsTotal += msSince(t0);
    return false;
  }
  KeyframeDatabase::Query q;
  q.minScore = *std::min_element(scores.begin(), scores.end());
  const std::set<int> own(neighbours.begin(), neighbours.end());
  q.excluded = [&](int c) {
    const auto it = m_keyframes.find(c);
    return c == id || connected.count(c) > 0 || own.count(c) > 0 || it == m_keyframes.end() ||
           it->second.segment != m_segment;
  };
  // Only the first groupNeighbours count: a keyframe of a room revisited lap after lap is co-visible with hundreds.
  const size_t groupNeighbours = static_cast<size_t>(std::max(0, m_database.options().groupNeighbours));
  q.covisible = [&](int c) { return map.covisibleWith(c, groupNeighbours); };
  std::vector<std::pair<int, std::vector<int>>> groups;
  for (const KeyframeDatabase::Candidate &c : m_database.query(bow, q)) {
    groups.emplace_back(c.id, map.covisibleWith(c.id));
  }
  const std::vector<int> accepted = groups.empty() ? std::vector<int>() : m_consistency.update(groups);
  if (groups.empty()) {
    m_consistency.clear();
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << id << ": loop query, min score " << q.minScore << ", " << groups.size()
                                              << " candidates, " << accepted.size() << " consistent");
  bool found = false;
  for (size_t k = 0; k < accepted.size() && !found; ++k) {
    const auto tv = std::chrono::steady_clock::now();
    found = verifyCandidate(id, accepted[k], map, loop);
    const double ms = msSince(tv);
    m_stats.verificationMsMax = std::max(m_stats.verificationMsMax, ms);
    m_stats.verificationMsTotal += ms;
  }
  m_stats.detectionMsTotal += msSince(t0);
  if (found) {
    m_keyframeOfLastLoop = m_keyframesInSegment;
    m_consistency.clear();
  }
  return found;
}

std::vector<LoopSideKeyframe> LoopCloser::side(int id, size_t neighbours, const GlobalMap &map,
                                               const std::set<int> &excluded) const
{
  std::vector<LoopSideKeyframe> out;
  const GlobalKeyframe *first = map.find(id);
  const auto self = m_keyframes.find(id);
  if (!first || self == m_keyframes.end()) {
    return out;
  }
  out.push_back({&self->second.features, SE3d()});
  for (int n : map.covisibleWith(id)) {
    if (out.size() > neighbours) {
      break;
    }
    const GlobalKeyframe *g = map.find(n);
    const auto it = m_keyframes.find(n);
    if (g && it != m_keyframes.end() && it->second.segment == self->second.segment && !excluded.count(n)) {
      out.push_back({&it->second.features, first->cMw * g->cMw.inverse()});
    }
  }
  return out;
}

bool LoopCloser::verifyCandidate(int id, int candidate, const GlobalMap &map, DetectedLoop &loop)
{
  ++m_stats.candidatesVerified;
  LoopVerificationOptions o;
  o.maxDistance = m_params.matchMaxDistance;
  o.ratio = m_params.matchRatio;
  o.minMatches = m_params.minMatches;
  o.minInliers = m_params.minInliers;
  o.thresholdPx = m_params.ransacThresholdPx;
  o.seed = static_cast<unsigned int>(id);
  LoopVerification v;
  try {
    // The candidate's side shares no keyframe with the query's nor with what the query sees: two sides holding the
    // same keyframe (a neighbour of both ends of a short loop) match it with itself, a perfect and meaningless fit.
    const std::vector<LoopSideKeyframe> query = side(id, kQueryNeighbours, map, {});
    std::set<int> querySide = {id};
    for (int n : map.covisibleWith(id)) {
      querySide.insert(n);
    }
    v = verifyLoopSides(query, side(candidate, kCandidateNeighbours, map, querySide), m_K, o);
  } catch (const vpHSlamException &e) { // a degenerate configuration: this candidate is not a loop
    VP_HSLAM_LOG(vpHSlamLog::warning, "keyframe " << id << ": loop candidate " << candidate
                                                  << " could not be verified: " << e.getStringMessage());
    return false;
  }
  const bool verified = v.estimate.success;
  VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << id << ": loop candidate " << candidate << ", " << v.matches
                                             << " ORB matches, " << v.guidedMatches << " guided, "
                                             << v.estimate.inlierCount << " Sim(3) inliers (" << v.centralInliers
                                             << " between the two)" << (verified ? " (accepted)" : " (rejected)"));
  if (!verified) {
    return false;
  }
  // The correction of the current estimate: where the candidate's side says the keyframe is, against its pose.
  const Sim3d current(map.find(id)->cMw * map.find(candidate)->cMw.inverse(), 1.);
  const Sim3d::Tangent drift = (v.estimate.S21 * current.inverse()).log();
  const double rotationDeg = drift.segment<3>(3).norm() * 180. / M_PI;
  if (rotationDeg > m_params.maxRotationCorrectionDeg) {
    // Odometry drifts a few degrees in rotation, not tens: a correction that large is a place that looks like
    // another (a repeated texture, two alike doors), however consistent its geometry.
    VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << id << ": loop with keyframe " << candidate
                                               << " refused: it would rotate the map by " << rotationDeg << " degrees");
    ++m_stats.refusedImplausible;
    return false;
  }
  loop.keyframe = id;
  loop.candidate = candidate;
  loop.SkeyframeCandidate = v.estimate.S21;
  LoopRecord record;
  record.keyframe = id;
  record.candidate = candidate;
  record.inliers = v.estimate.inlierCount;
  record.scale = v.estimate.S21.scale();
  record.translationDrift = drift.head<3>().norm();
  m_stats.loops.push_back(record);
  VP_HSLAM_LOG(vpHSlamLog::info, "keyframe " << id << ": loop with keyframe " << candidate << " (" << record.inliers
                                             << " inliers, scale " << record.scale << ", translation correction "
                                             << record.translationDrift << ", rotation correction " << rotationDeg
                                             << " degrees)");
  return true;
}

bool LoopCloser::correct(const DetectedLoop &loop, const GlobalMap &map, const std::map<int, SE3d> &windowPoses,
                         std::vector<std::pair<int, Sim3d>> &solution)
{
  const GlobalKeyframe *g = map.find(loop.keyframe);
  bool ok = false;
  try {
    ok = g && solveLoopCorrection(map, g->segment, windowPoses, m_loopConstraints, loop, solution, m_landmarks);
    for (size_t i = 0; ok && i < solution.size(); ++i) {
      rescale(solution[i].first, solution[i].second.scale()); // the loop features follow their keyframe's map
    }
  } catch (const vpHSlamException &e) { // nothing is changed before the pose graph succeeded
    VP_HSLAM_LOG(vpHSlamLog::warning,
                 "loop " << loop.keyframe << "-" << loop.candidate << ": " << e.getStringMessage());
  }
  if (!ok) {
    VP_HSLAM_LOG(vpHSlamLog::warning, "loop " << loop.keyframe << "-" << loop.candidate << " not corrected");
  }
  return ok;
}

void LoopCloser::setLandmarkSightings(LandmarkSightings landmarks)
{
  if (!m_thread.joinable()) {
    m_landmarks = std::move(landmarks);
    return;
  }
  Work work;
  work.kind = Work::newSightings;
  work.landmarks = std::move(landmarks);
  enqueue(std::move(work));
}

bool LoopCloser::solve(Correction &correction, const GlobalMap &map, const std::map<int, SE3d> &windowPoses)
{
  return correction.landmark ? correctLandmarks(correction.loop.keyframe, map, windowPoses, correction.solution)
                             : correct(correction.loop, map, windowPoses, correction.solution);
}

bool LoopCloser::correctLandmarks(int keyframe, const GlobalMap &map, const std::map<int, SE3d> &windowPoses,
                                  std::vector<std::pair<int, Sim3d>> &solution)
{
  const GlobalKeyframe *g = map.find(keyframe);
  const int segment = g ? g->segment : m_segment; // the keyframe is usually still in the window
  bool ok = false;
  try {
    ok = solveLandmarkCorrection(map, segment, windowPoses, m_loopConstraints, m_landmarks, solution);
    for (size_t i = 0; ok && i < solution.size(); ++i) {
      rescale(solution[i].first, solution[i].second.scale());
    }
  } catch (const vpHSlamException &e) { // nothing is changed before the pose graph succeeded
    VP_HSLAM_LOG(vpHSlamLog::warning, "landmark correction at keyframe " << keyframe << ": " << e.getStringMessage());
    ok = false;
  }
  return ok;
}

void LoopCloser::queueLandmarkCorrection(int keyframe, GlobalMap graph, std::map<int, SE3d> windowPoses)
{
  Work work;
  work.kind = Work::landmarkCorrection;
  work.id = keyframe;
  work.graph = std::move(graph);
  work.windowPoses = std::move(windowPoses);
  {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    work.correctionsApplied = m_correctionsTaken;
  }
  enqueue(std::move(work));
}

void LoopCloser::handOver(const Keyframe &kf, int segment, const std::vector<KeyframePtr> &window)
{
  // Depth samples: the keyframe's own points (final now) and the window's active points seen from it.
  std::vector<IdepthSample> samples;
  for (const KeyframePtr &host : window) {
    const bool own = host.get() == &kf;
    const SE3d kMh = kf.frame->cMw * host->frame->cMw.inverse();
    for (const MapPoint &p : host->points) {
      const bool usable = p.status == PointStatus::active || (own && p.status == PointStatus::marginalized);
      if (!usable || !(p.idepth > 0.) || p.depthFromPrior) {
        continue;
      }
      const Eigen::Vector3d X = own ? m_K.unproject(p.u, p.v, p.idepth) : kMh * m_K.unproject(p.u, p.v, p.idepth);
      if (X.z() > 0.) {
        const Eigen::Vector2d uv = m_K.project(X);
        samples.push_back({uv.x(), uv.y(), 1. / X.z()});
      }
    }
  }
  if (!m_thread.joinable()) {
    addKeyframe(kf.id(), segment, kf.frame->raw, samples);
    return;
  }
  Work work;
  work.kind = Work::handOver;
  work.id = kf.id();
  work.segment = segment;
  work.image = kf.frame->raw; // a copy: the keyframe's image is released once it is stored
  work.samples = std::move(samples);
  enqueue(std::move(work));
}

std::set<int> LoopCloser::connectedTo(const std::vector<KeyframePtr> &window)
{
  // Not the window's co-visible keyframes: the query is a stored keyframe now, and a keyframe DSO keeps in the window
  // for long (it still sees most of its points) is co-visible with a whole pass; with them, every keyframe of the
  // outward pass was excluded on 7-Scenes played there and back. The query's own co-visible ones are excluded by
  // the loop closer.
  std::set<int> connected;
  for (const KeyframePtr &kf : window) {
    connected.insert(kf->id());
    // Keyframes whose points the window re-uses now are connected (their co-visibility is only counted once those
    // points leave the window again): re-use has already joined them to the present, no loop is needed there.
    for (const MapPoint &pt : kf->points) {
      if (pt.status == PointStatus::active && pt.fromGlobalMap) {
        connected.insert(pt.observers.begin(), pt.observers.end());
      }
    }
  }
  return connected;
}

std::unique_ptr<GlobalBundleJob> LoopCloser::makeGlobalBundleJob(const GlobalMap &map, int segment,
                                                                 const std::map<int, SE3d> &windowPoses)
{
  GlobalBundleOptions options;
  options.maxIterations = m_params.globalBaIterations;
  options.huberPx = m_params.globalBaHuberPx;
  ++m_applied.globalBaStarted;
  return hslam::makeGlobalBundleJob(map, segment, windowPoses, m_K, options, m_params.globalBaPointsPerKeyframe);
}

std::unique_ptr<GlobalBundleJob> LoopCloser::takeBackgroundJob(bool wait)
{
  if (!m_globalBa.running() || (!wait && !m_globalBa.finished())) {
    return nullptr;
  }
  return m_globalBa.take();
}

void LoopCloser::rescale(int id, double scale)
{
  const auto it = m_keyframes.find(id);
  if (it != m_keyframes.end() && scale > 0. && scale != 1.) {
    it->second.features.rescale(scale);
  }
}

void LoopCloser::removeKeyframe(int id)
{
  if (!m_thread.joinable()) {
    dropKeyframe(id);
    return;
  }
  Work work;
  work.kind = Work::remove;
  work.id = id;
  enqueue(std::move(work));
}

void LoopCloser::dropKeyframe(int id)
{
  m_database.remove(id);
  m_keyframes.erase(id);
  m_pending.erase(std::remove(m_pending.begin(), m_pending.end(), id), m_pending.end());
}

void LoopCloser::newSegment()
{
  m_consistency.clear();
  m_keyframesInSegment = 0;
  m_keyframeOfLastLoop = 0;
}

void LoopCloser::clear()
{
  m_globalBa.cancel();
  if (m_thread.joinable()) {
    std::unique_lock<std::mutex> lock(m_queueMutex);
    waitIdle(lock); // the thread holds no state now, and takes none until more work is queued
    m_corrections.clear();
    m_correctionsSolved = 0;
    m_correctionsTaken = 0;
  }
  m_database.clear();
  m_keyframes.clear();
  m_pending.clear();
  m_loopConstraints.clear();
  m_landmarks = LandmarkSightings();
  m_segment = 0;
  newSegment();
}

double LoopCloser::memoryBytes() const
{
  if (m_thread.joinable()) {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    return m_publishedBytes;
  }
  return heldBytes();
}

double LoopCloser::heldBytes() const
{
  double bytes = m_database.memoryBytes() + mapNodesHeapBytes(m_keyframes) + vectorHeapBytes(m_loopConstraints);
  for (const auto &entry : m_keyframes) {
    bytes += entry.second.features.memoryBytes();
  }
  return bytes;
}

LoopStatistics LoopCloser::statistics() const
{
  LoopStatistics s;
  if (m_thread.joinable()) {
    std::lock_guard<std::mutex> lock(m_queueMutex);
    s = m_published;
  } else {
    s = m_stats;
  }
  s.applied = m_applied;
  return s;
}

void LoopCloser::recordCorrectionApplied(double ms, bool landmark)
{
  ++(landmark ? m_applied.landmarkCorrected : m_applied.corrected);
  m_applied.lastCorrectionMs = ms;
  m_applied.correctionMsMax = std::max(m_applied.correctionMsMax, ms);
}

void LoopCloser::recordGlobalBundleAdjustment(const GlobalBundleSummary &summary, bool applied)
{
  m_applied.globalBaSecondsMax = std::max(m_applied.globalBaSecondsMax, summary.seconds);
  if (applied) {
    ++m_applied.globalBaApplied;
    m_applied.globalBaRmsBeforePx = summary.rmsBeforePx;
    m_applied.globalBaRmsAfterPx = summary.rmsAfterPx;
  }
}

void LoopCloser::resetStatistics()
{
  if (m_thread.joinable()) {
    std::unique_lock<std::mutex> lock(m_queueMutex);
    waitIdle(lock);
    m_published = LoopStatistics();
  }
  m_stats = LoopStatistics();
  m_applied = LoopApplyStatistics();
}
} // namespace hslam
