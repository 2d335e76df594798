/*
 * H-SLAM for ViSP.
 */
// LocalMapper's outputs: the tracking reference, keyframe states, points and counts, memory (LocalMapper.h).
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include "tracking/CoarseTracker.h"

#include <vector>

namespace hslam
{
bool LocalMapper::prepareTrackingReference(CoarseTracker &tracker, int &keyframeId, AffineBrightness &affine,
                                           double &exposure) const
{
  const Impl &m = *m_impl;
  if (m_window.empty() || m.referenceKeyframe < 0) {
    return false;
  }
  KeyframePtr ref;
  for (const KeyframePtr &kf : m_window) {
    if (kf->id() == m.referenceKeyframe) {
      ref = kf;
    }
  }
  if (!ref) {
    return false;
  }
  tracker.setReference(*ref->frame, m.referencePoints);
  tracker.setReferenceFeatures(m.referenceFeatures);
  keyframeId = ref->id();
  affine = ref->frame->affine;
  exposure = ref->frame->exposure;
  return true;
}

void LocalMapper::takeKeyframeStates(std::vector<KeyframeState> &states)
{
  states = m_impl->marginalizedStates;
  m_impl->marginalizedStates.clear();
  for (const KeyframePtr &kf : m_window) {
    KeyframeState s;
    s.id = kf->id();
    s.wMc = kf->frame->cMw.inverse();
    s.inWindow = true;
    for (const MapPoint &p : kf->points) {
      s.activePoints += p.status == PointStatus::active ? 1u : 0u;
    }
    states.push_back(s);
  }
}

void LocalMapper::activePointsWorld(std::vector<Eigen::Vector3d> &points) const
{
  points.clear();
  const PinholeIntrinsics &K = m_impl->K0;
  for (const KeyframePtr &kf : m_window) {
    const SE3d wMc = kf->frame->cMw.inverse();
    for (const MapPoint &p : kf->points) {
      if (p.status != PointStatus::active || !(p.idepth > 0.)) {
        continue;
      }
      const Eigen::Vector3d cX((p.u - K.cx) / K.fx / p.idepth, (p.v - K.cy) / K.fy / p.idepth, 1. / p.idepth);
      points.push_back(wMc * cX);
    }
  }
}

int LocalMapper::activePointCount() const
{
  int n = 0;
  for (const KeyframePtr &kf : m_window) {
    for (const MapPoint &p : kf->points) {
      n += p.status == PointStatus::active ? 1 : 0;
    }
  }
  return n;
}

int LocalMapper::immaturePointCount() const
{
  int n = 0;
  for (const KeyframePtr &kf : m_window) {
    n += static_cast<int>(kf->immature.size());
  }
  return n;
}

double LocalMapper::windowMemoryBytes() const
{
  double bytes = 0.;
  for (const KeyframePtr &kf : m_window) {
    const ImagePyramid &pyr = kf->frame->pyramid;
    for (int l = 0; l < pyr.numLevels(); ++l) {
      const PyramidLevel &level = pyr.level(l);
      bytes += static_cast<double>(level.color.capacity() * sizeof(Eigen::Vector3f) +
                                   level.gradSq.capacity() * sizeof(float));
    }
    bytes += static_cast<double>(kf->frame->raw.getSize());
    bytes +=
        static_cast<double>(kf->points.capacity() * sizeof(MapPoint) + kf->immature.capacity() * sizeof(ImmaturePoint));
  }
  return bytes;
}

double LocalMapper::marginalizedMemoryBytes() const
{
  double bytes = m_globalMap.memoryBytes() + loopMemoryBytes();
  if (m_impl->relocalization) {
    bytes += m_impl->relocalization->memoryBytes();
  }
  return bytes;
}

SE3d LocalMapper::newestKeyframe_cMw() const
{
  return m_window.empty() ? SE3d() : m_window.back()->frame->cMw;
}

int LocalMapper::newestKeyframeId() const
{
  return m_window.empty() ? -1 : m_window.back()->id();
}
} // namespace hslam
