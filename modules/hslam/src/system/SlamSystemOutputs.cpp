/*
 * H-SLAM for ViSP.
 */
// What SlamSystem gives out (pose, keyframes, points, statistics, display data); any thread. See SlamSystem.h.
#include "system/SlamSystem.h"

#include "math/ViSPConversions.h"

namespace hslam
{
vpHomogeneousMatrix SlamSystem::get_cMw() const
{
  SE3d wMc;
  if (m_recorder.lastFramePose(wMc)) {
    return toVpHomogeneousMatrix(wMc.inverse());
  }
  return vpHomogeneousMatrix();
}

bool SlamSystem::hasPose() const
{
  return m_recorder.frameCount() > 0;
}

std::vector<vpHSlam::Keyframe> SlamSystem::keyframes() const
{
  const std::vector<TrajectoryRecorder::KeyframeRecord> records = m_recorder.keyframes();
  std::vector<vpHSlam::Keyframe> out;
  out.reserve(records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    if (records[i].discarded) {
      continue;
    }
    vpHSlam::Keyframe k;
    k.id = static_cast<unsigned int>(records[i].id);
    k.frameIndex = static_cast<unsigned int>(records[i].frameIndex);
    k.timestamp = records[i].timestamp;
    k.wMc = toVpHomogeneousMatrix(records[i].wMc);
    k.inWindow = records[i].inWindow;
    k.segment = records[i].segment;
    k.activePoints = records[i].activePoints;
    out.push_back(k);
  }
  return out;
}

std::vector<vpColVector> SlamSystem::activePoints(std::vector<double> *depths) const
{
  std::vector<Eigen::Vector3d> points;
  {
    std::lock_guard<std::mutex> lock(m_snapshotMutex);
    points = m_snapshotPoints;
  }
  SE3d wMc;
  const bool havePose = m_recorder.lastFramePose(wMc);
  const SE3d cMw = wMc.inverse();
  std::vector<vpColVector> out;
  out.reserve(points.size());
  if (depths) {
    depths->clear();
    depths->reserve(points.size());
  }
  for (const Eigen::Vector3d &p : points) {
    vpColVector v(3);
    v[0] = p.x();
    v[1] = p.y();
    v[2] = p.z();
    out.push_back(v);
    if (depths) {
      depths->push_back(havePose ? (cMw * p).z() : p.z());
    }
  }
  return out;
}

vpHSlam::Statistics SlamSystem::statistics() const
{
  vpHSlam::Statistics s;
  s.frames = m_frames.load();
  s.trackedFrames = m_trackedFrames.load();
  s.keyframes = static_cast<unsigned int>(m_recorder.keyframeCount());
  s.segments = m_segmentsStarted;
  s.lostFrames = m_lostFrames.load();
  s.mappingSkippedFrames = m_mappingSkipped.load();
  const RunStatistics::Summary t = m_runStats.summary();
  s.trackingMsMedian = t.trackingMsMedian;
  s.trackingMsP95 = t.trackingMsP95;
  s.trackingMsMax = t.trackingMsMax;
  s.initializationMsMedian = t.initializationMsMedian;
  s.mappingMsPerKeyframeMedian = t.keyframeMsMedian;
  s.mappingMsPerKeyframeP95 = t.keyframeMsP95;
  s.mappingMsPerFrameMedian = t.frameMappingMsMedian;
  std::lock_guard<std::mutex> lock(m_snapshotMutex);
  s.activePoints = static_cast<unsigned int>(m_snapshotPoints.size());
  s.immaturePoints = m_snapshotImmature;
  s.mapMemoryMb = m_snapshotMemoryMb;
  s.keyframesHeld = m_snapshotKeyframesHeld;
  const LocalMapper::ReuseStatistics &r = m_snapshotReuse;
  s.marginalizedMemoryMb = m_snapshotMarginalizedMb;
  s.marginalizedKeyframes = static_cast<unsigned int>(r.storedKeyframes);
  // Per keyframe: what one more keyframe costs once it has left the window (the window's own keyframes are a
  // fixed cost); with nothing stored (vo-strict), the window's memory per keyframe.
  if (r.storedKeyframes > 0) {
    s.mapMemoryMbPerKeyframe = m_snapshotMarginalizedMb / r.storedKeyframes;
  } else {
    s.mapMemoryMbPerKeyframe = m_snapshotKeyframesHeld > 0 ? m_snapshotMemoryMb / m_snapshotKeyframesHeld : 0.;
  }
  s.culledKeyframes = static_cast<unsigned int>(r.culledKeyframes);
  s.globalPoints = static_cast<unsigned int>(r.storedPoints);
  s.reactivatedPointsPerKeyframe = r.keyframes > 0 ? static_cast<double>(r.reactivated) / r.keyframes : 0.;
  s.fusedPointsPerKeyframe = r.keyframes > 0 ? static_cast<double>(r.fused) / r.keyframes : 0.;
  const LocalMapper::LoopStatistics &loops = m_snapshotLoopStats;
  s.loopsDetected = static_cast<unsigned int>(loops.loops.size());
  s.loopCandidatesVerified = static_cast<unsigned int>(loops.candidatesVerified);
  s.loopsCorrected = static_cast<unsigned int>(loops.corrected);
  s.lastLoopCorrectionMs = loops.lastCorrectionMs;
  s.loopCorrectionMsMax = loops.correctionMsMax;
  s.loopDetectionMsMean = loops.detections > 0 ? loops.detectionMsTotal / loops.detections : 0.;
  s.loopVerificationMsMax = loops.verificationMsMax;
  s.globalBundleAdjustments = static_cast<unsigned int>(loops.globalBaStarted);
  s.globalBundleAdjustmentsApplied = static_cast<unsigned int>(loops.globalBaApplied);
  s.globalBundleAdjustmentSecondsMax = loops.globalBaSecondsMax;
  s.globalBundleAdjustmentRmsBeforePx = loops.globalBaRmsBeforePx;
  s.globalBundleAdjustmentRmsAfterPx = loops.globalBaRmsAfterPx;
  s.framesDuringLoopCorrection = static_cast<unsigned int>(t.framesDuringLoopCorrection);
  s.trackingMsMaxDuringLoopCorrection = t.trackingMsMaxDuringLoopCorrection;
  s.windowShareFromGlobal = r.windowActive > 0 ? static_cast<double>(r.windowFromGlobal) / r.windowActive : 0.;
  s.orbMatchesMedian = t.orbMatchesMedian;
  s.orbInliersMedian = t.orbInliersMedian;
  s.geometricWeightMedian = t.geometricWeightMedian;
  s.relocalizationsAttempted = m_relocAttempts.load();
  s.relocalizationsSucceeded = m_relocSuccesses.load();
  s.descriptorKbPerKeyframe = m_snapshotDescriptorKb;
  return s;
}

std::vector<vpImagePoint> SlamSystem::descriptorMatches() const
{
  std::lock_guard<std::mutex> lock(m_imageMutex);
  return m_lastMatches;
}

std::vector<vpHSlam::MapPoint> SlamSystem::mapPoints() const
{
  std::vector<Eigen::Vector3d> points;
  std::vector<int> status;
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    if (m_mapper) {
      m_mapper->mapPointsWorld(points, status);
    }
  }
  std::vector<vpHSlam::MapPoint> out(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    out[i].wX.resize(3);
    for (unsigned int k = 0; k < 3; ++k) {
      out[i].wX[k] = points[i][static_cast<int>(k)];
    }
    out[i].active = status[i] == 0;
  }
  return out;
}

std::vector<vpHSlam::GraphEdge> SlamSystem::graphEdges() const
{
  std::vector<vpHSlam::GraphEdge> out;
  std::lock_guard<std::mutex> lock(m_mapperMutex);
  if (!m_mapper) {
    return out;
  }
  const GlobalMap &map = m_mapper->globalMap();
  for (const CovisibilityEdge &e : map.covisibilityEdges()) {
    vpHSlam::GraphEdge g;
    g.a = static_cast<unsigned int>(e.a);
    g.b = static_cast<unsigned int>(e.b);
    g.covisibility = true;
    g.weight = static_cast<unsigned int>(e.weight);
    out.push_back(g);
  }
  for (const PosePoseEdge &e : map.posePoseEdges()) {
    vpHSlam::GraphEdge g;
    g.a = static_cast<unsigned int>(e.from);
    g.b = static_cast<unsigned int>(e.to);
    out.push_back(g);
  }
  return out;
}

void SlamSystem::rectifiedImage(vpImage<unsigned char> &I) const
{
  std::lock_guard<std::mutex> lock(m_imageMutex);
  I = m_lastImage;
}
} // namespace hslam
