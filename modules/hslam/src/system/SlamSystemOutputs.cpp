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
    k.id = static_cast<unsigned int>(i);
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
  s.mapMemoryMbPerKeyframe = m_snapshotKeyframesHeld > 0 ? m_snapshotMemoryMb / m_snapshotKeyframesHeld : 0.;
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

void SlamSystem::rectifiedImage(vpImage<unsigned char> &I) const
{
  std::lock_guard<std::mutex> lock(m_imageMutex);
  I = m_lastImage;
}
} // namespace hslam
