/*
 * H-SLAM for ViSP.
 */
#include "system/TrajectoryRecorder.h"

#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <map>
#include <string>

namespace hslam
{
void TrajectoryRecorder::addKeyframe(int keyframeId, int frameIndex, double timestamp, const SE3d &wMc,
                                     unsigned int segment)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  const int expected = m_firstId + static_cast<int>(m_keyframes.size());
  if (keyframeId != expected) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ": keyframe id " +
                                                                  std::to_string(keyframeId) + " recorded, " +
                                                                  std::to_string(expected) + " expected");
  }
  KeyframeRecord r;
  r.id = keyframeId;
  r.frameIndex = frameIndex;
  r.timestamp = timestamp;
  r.wMc = wMc;
  r.segment = segment;
  m_keyframes.push_back(r);
}

void TrajectoryRecorder::setFirstKeyframeId(int id)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_keyframes.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ": first keyframe id set after keyframes were recorded");
  }
  m_firstId = id;
}

TrajectoryRecorder::KeyframeRecord *TrajectoryRecorder::findLocked(int id)
{
  const int index = id - m_firstId;
  return index >= 0 && index < static_cast<int>(m_keyframes.size()) ? &m_keyframes[static_cast<size_t>(index)]
                                                                    : nullptr;
}

const TrajectoryRecorder::KeyframeRecord *TrajectoryRecorder::findLocked(int id) const
{
  return const_cast<TrajectoryRecorder *>(this)->findLocked(id);
}

void TrajectoryRecorder::updateKeyframe(int keyframeId, const SE3d &wMc)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  if (KeyframeRecord *k = findLocked(keyframeId)) {
    k->wMc = wMc;
  }
}

void TrajectoryRecorder::correctKeyframes(const std::vector<int> &ids, const std::vector<SE3d> &wMc,
                                          const std::vector<double> &scale)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  std::map<int, double> factor; // keyframe id -> scale of its correction, when not 1
  for (size_t i = 0; i < ids.size() && i < wMc.size() && i < scale.size(); ++i) {
    KeyframeRecord *k = findLocked(ids[i]);
    if (k && scale[i] > 0.) {
      k->wMc = wMc[i];
      if (scale[i] != 1.) {
        factor[ids[i]] = scale[i];
      }
    }
  }
  for (FrameRecord &f : m_frames) {
    auto it = factor.find(f.referenceKeyframe);
    if (it != factor.end()) {
      f.refMc = SE3d(f.refMc.unitQuaternion(), f.refMc.translation() / it->second);
    }
  }
}

void TrajectoryRecorder::setKeyframeInWindow(int keyframeId, bool inWindow, unsigned int activePoints)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  if (KeyframeRecord *k = findLocked(keyframeId)) {
    k->inWindow = inWindow;
    k->activePoints = activePoints;
  }
}

void TrajectoryRecorder::addFrame(int frameIndex, double timestamp, int referenceKeyframe, const SE3d &refMc,
                                  unsigned int segment)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  if (frameIndex < 0) {
    return;
  }
  FrameRecord r;
  r.frameIndex = frameIndex;
  r.timestamp = timestamp;
  r.referenceKeyframe = referenceKeyframe;
  r.refMc = refMc;
  r.segment = segment;
  if (static_cast<size_t>(frameIndex) >= m_frameSlot.size()) {
    m_frameSlot.resize(static_cast<size_t>(frameIndex) + 1, -1);
  }
  int &slot = m_frameSlot[static_cast<size_t>(frameIndex)];
  if (slot >= 0) {
    m_frames[static_cast<size_t>(slot)] = r;
  } else {
    slot = static_cast<int>(m_frames.size());
    m_frames.push_back(r);
  }
}

SE3d TrajectoryRecorder::worldPoseLocked(const FrameRecord &f) const
{
  const KeyframeRecord *k = findLocked(f.referenceKeyframe);
  return k ? k->wMc * f.refMc : f.refMc; // without a keyframe: anchored to the world itself
}

SE3d TrajectoryRecorder::keyframePose(int keyframeId) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  const KeyframeRecord *k = findLocked(keyframeId);
  if (!k) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ": unknown keyframe id " + std::to_string(keyframeId));
  }
  return k->wMc;
}

bool TrajectoryRecorder::keptKeyframePose(int keyframeId, SE3d &wMc) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  const KeyframeRecord *k = findLocked(keyframeId);
  if (!k || k->discarded) {
    return false;
  }
  wMc = k->wMc;
  return true;
}

bool TrajectoryRecorder::lastFramePose(SE3d &wMc) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  for (auto it = m_frameSlot.rbegin(); it != m_frameSlot.rend(); ++it) {
    if (*it >= 0) {
      wMc = worldPoseLocked(m_frames[static_cast<size_t>(*it)]);
      return true;
    }
  }
  return false;
}

bool TrajectoryRecorder::framePose(int frameIndex, SE3d &wMc) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  if (frameIndex < 0 || static_cast<size_t>(frameIndex) >= m_frameSlot.size() ||
      m_frameSlot[static_cast<size_t>(frameIndex)] < 0) {
    return false;
  }
  wMc = worldPoseLocked(m_frames[static_cast<size_t>(m_frameSlot[static_cast<size_t>(frameIndex)])]);
  return true;
}

size_t TrajectoryRecorder::frameCount() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_frames.size();
}

size_t TrajectoryRecorder::keyframeCount() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  size_t n = 0;
  for (const KeyframeRecord &k : m_keyframes) {
    n += k.discarded ? 0 : 1;
  }
  return n;
}

size_t TrajectoryRecorder::discardSegment(unsigned int segment)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  for (KeyframeRecord &k : m_keyframes) {
    if (k.segment == segment) {
      k.discarded = true;
      k.inWindow = false;
    }
  }
  const size_t before = m_frames.size();
  m_frames.erase(std::remove_if(m_frames.begin(), m_frames.end(),
                                [segment](const FrameRecord &f) { return f.segment == segment; }),
                 m_frames.end());
  std::fill(m_frameSlot.begin(), m_frameSlot.end(), -1);
  for (size_t i = 0; i < m_frames.size(); ++i) {
    m_frameSlot[static_cast<size_t>(m_frames[i].frameIndex)] = static_cast<int>(i);
  }
  return before - m_frames.size();
}

std::vector<TrajectoryRecorder::KeyframeRecord> TrajectoryRecorder::keyframes() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_keyframes;
}

vpHSlamTrajectory TrajectoryRecorder::trajectory(int segment, std::vector<unsigned int> *segments) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  vpHSlamTrajectory traj;
  if (segments) {
    segments->clear();
  }
  for (int slot : m_frameSlot) { // frame index order, whatever the order of recording
    if (slot < 0) {
      continue;
    }
    const FrameRecord &f = m_frames[static_cast<size_t>(slot)];
    if (segment < 0 || f.segment == static_cast<unsigned int>(segment)) {
      traj.add(f.timestamp, toVpHomogeneousMatrix(worldPoseLocked(f)));
      if (segments) {
        segments->push_back(f.segment);
      }
    }
  }
  return traj;
}

vpHSlamTrajectory TrajectoryRecorder::keyframeTrajectory(int segment, std::vector<unsigned int> *segments) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  vpHSlamTrajectory traj;
  if (segments) {
    segments->clear();
  }
  for (const KeyframeRecord &k : m_keyframes) {
    if (!k.discarded && (segment < 0 || k.segment == static_cast<unsigned int>(segment))) {
      traj.add(k.timestamp, toVpHomogeneousMatrix(k.wMc));
      if (segments) {
        segments->push_back(k.segment);
      }
    }
  }
  return traj;
}

std::vector<unsigned int> TrajectoryRecorder::frameSegments() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  std::vector<unsigned int> segments;
  segments.reserve(m_frames.size());
  for (int slot : m_frameSlot) {
    if (slot >= 0) {
      segments.push_back(m_frames[static_cast<size_t>(slot)].segment);
    }
  }
  return segments;
}

void TrajectoryRecorder::clear()
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_keyframes.clear();
  m_firstId = 0;
  m_frames.clear();
  m_frameSlot.clear();
}
} // namespace hslam
