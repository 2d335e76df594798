/*
 * H-SLAM for ViSP.
 */
// LocalMapper's side of relocalisation: keyframe points in world coordinates, candidates for a lost frame, the
// memory descriptors add. See LocalMapper.h and tracking/RelocalizationIndex.h.
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"
#include "tracking/WindowRelocalization.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! Relocalisation matches a lost frame against a candidate keyframe's points and those of the keyframes this many
//! ids before and after it.
constexpr int kRelocalizationNeighbours = 2;
//! DSO makeCoarseDepthL0: a point's weight in a tracking reference is sqrt(1e-3 * H_idepth) (as the window's).
constexpr double kStoredTrackingWeightScale = 1e-3;
} // namespace

// Corners only, as for tracking (gradient pixels' descriptors are not where a keypoint would be); measured on
// 7scenes_redkitchen_000-299 with frames 120-135 black: relocalised after 16 lost frames, 20 with every point.
void LocalMapper::keyframePointsWorld(const Keyframe &kf, RelocalizationKeyframe &out) const
{
  const Impl &m = *m_impl;
  out.id = kf.id();
  out.wX.clear();
  out.descriptors.clear();
  const SE3d wMc = kf.frame->cMw.inverse();
  for (const MapPoint &p : kf.points) {
    if (p.status == PointStatus::outlier || !p.hasOrb || !(p.idepth > 0.) || !p.isCorner) {
      continue;
    }
    out.wX.push_back(wMc * m.K0.unproject(p.u, p.v, p.idepth));
    out.descriptors.push_back(p.orb);
  }
}

double LocalMapper::descriptorBytesPerKeyframe() const
{
  const Impl &m = *m_impl;
  if (!m.selector.withDescriptors() || m_window.empty()) {
    return 0.;
  }
  // What a descriptor adds to a point: the descriptor, its angle and its flag (padding included by sizeof
  // differences would overstate it; these are the members added for descriptor sharing).
  constexpr double kPerPoint = sizeof(OrbDescriptor) + sizeof(float) + sizeof(bool);
  double points = 0.;
  for (const KeyframePtr &kf : m_window) {
    points += static_cast<double>(kf->points.size() + kf->immature.size());
  }
  double bytes = kPerPoint * points / static_cast<double>(m_window.size());
  if (m.relocalization && m.relocalization->size() > 0) {
    bytes += m.relocalization->memoryBytes() / static_cast<double>(m.relocalization->size());
  }
  return bytes;
}

bool LocalMapper::indexGlobalMap()
{
  Impl &m = *m_impl;
  if (!m.relocalization) {
    return false;
  }
  for (const auto &entry : m_globalMap.keyframes()) {
    const GlobalKeyframe &kf = entry.second;
    if (kf.culled) {
      continue; // as when the map was built: a culled keyframe left the database
    }
    std::vector<OrbDescriptor> described;
    std::vector<Eigen::Vector3d> wX;
    std::vector<OrbDescriptor> corners;
    const SE3d wMc = kf.cMw.inverse();
    for (const GlobalPoint &p : kf.points) {
      if (!p.hasOrb) {
        continue;
      }
      described.push_back(p.orb);
      if (p.isCorner && p.state == GlobalPointState::stored && p.idepth > 0.f) { // as keyframePointsWorld()
        wX.push_back(wMc * m.K0.unproject(p.u, p.v, p.idepth));
        corners.push_back(p.orb);
      }
    }
    m.relocalization->addKeyframe(kf.id, described);
    m.relocalization->setKeyframePoints(kf.id, std::move(wX), std::move(corners));
  }
  return true;
}

std::vector<int> LocalMapper::storedNeighbourhood(int id) const
{
  std::vector<int> ids = m_globalMap.covisibleWith(id);
  for (int n = id - kRelocalizationNeighbours; n <= id + kRelocalizationNeighbours; ++n) {
    ids.push_back(n);
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<int> out;
  for (int n : ids) {
    const GlobalKeyframe *kf = m_globalMap.find(n);
    if (kf && !kf->culled) {
      out.push_back(n);
    }
  }
  return out;
}

void LocalMapper::localMapFeatures(int id, std::vector<ReferenceFeature> &features, std::vector<int> &keyframeIds) const
{
  const Impl &m = *m_impl;
  features.clear();
  keyframeIds = storedNeighbourhood(id);
  for (int n : keyframeIds) {
    const GlobalKeyframe *kf = m_globalMap.find(n);
    const SE3d wMc = kf->cMw.inverse();
    for (const GlobalPoint &p : kf->points) {
      if (!p.hasOrb || p.state != GlobalPointState::stored || !(p.idepth > 0.f)) {
        continue;
      }
      ReferenceFeature f;
      f.Xref = wMc * m.K0.unproject(p.u, p.v, p.idepth);
      f.orb = p.orb;
      f.angleDeg = p.orbAngleDeg;
      f.idepthVar = p.idepthVar;
      features.push_back(f);
    }
  }
}

void LocalMapper::localMapReference(const std::vector<int> &keyframeIds, const SE3d &refMw,
                                    std::vector<CoarseTrackerPoint> &points) const
{
  const Impl &m = *m_impl;
  points.clear();
  for (int id : keyframeIds) {
    const GlobalKeyframe *kf = m_globalMap.find(id);
    if (!kf) {
      continue;
    }
    const SE3d refMhost = refMw * kf->cMw.inverse();
    for (const GlobalPoint &p : kf->points) {
      if (p.state != GlobalPointState::stored || !(p.idepth > 0.f)) {
        continue;
      }
      // The window's tracking weight (DSO: sqrt(1e-3 H_idepth)) from the variance kept at marginalisation.
      const double weight = std::sqrt(kStoredTrackingWeightScale / std::max(static_cast<double>(p.idepthVar), 1e-12));
      CoarseTrackerPoint out;
      if (projectIntoReference(refMhost, m.K0, m.width, m.height, p.u, p.v, p.idepth, static_cast<float>(weight),
                               out)) {
        points.push_back(out);
      }
    }
  }
}

int LocalMapper::closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) const
{
  const Eigen::Vector3d centre = cMw.inverse().translation();
  int best = -1;
  double bestDistance = 0.;
  for (int id : keyframeIds) {
    const GlobalKeyframe *kf = m_globalMap.find(id);
    if (!kf) {
      continue;
    }
    const double d = (kf->cMw.inverse().translation() - centre).norm();
    if (best < 0 || d < bestDistance) {
      best = id;
      bestDistance = d;
    }
  }
  return best;
}

std::vector<WindowView> LocalMapper::windowViews() const
{
  std::vector<WindowView> views;
  for (const KeyframePtr &kf : m_window) {
    WindowView v;
    v.id = kf->id();
    v.cMw = kf->frame->cMw;
    v.frame = kf->frame;
    views.push_back(std::move(v));
  }
  return views;
}

bool LocalMapper::indexesKeyframes() const
{
  return m_impl->relocalization != nullptr;
}

std::vector<RelocalizationKeyframe> LocalMapper::relocalizationCandidates(RelocalizationFrame &frame, int maxCandidates,
                                                                          int preferred) const
{
  const Impl &m = *m_impl;
  std::vector<RelocalizationKeyframe> out;
  if (!m.relocalization) {
    return out;
  }
  BowVector bow;
  m.relocalization->describeFrame(frame, bow);
  std::vector<int> ids = m.relocalization->candidates(bow, maxCandidates);
  if (preferred >= 0 && std::find(ids.begin(), ids.end(), preferred) == ids.end()) {
    ids.insert(ids.begin(), preferred); // the caller's guess (the keyframe that placed the previous frame) first
  }
  for (int id : ids) {
    // The candidate and its neighbours in time (they see the same place; a keyframe alone hosts few points).
    RelocalizationKeyframe k;
    k.id = id;
    for (int n = id - kRelocalizationNeighbours; n <= id + kRelocalizationNeighbours; ++n) {
      RelocalizationKeyframe part;
      auto inWindow =
          std::find_if(m_window.begin(), m_window.end(), [n](const KeyframePtr &w) { return w->id() == n; });
      if (inWindow != m_window.end()) {
        keyframePointsWorld(**inWindow, part);
      } else if (!m.relocalization->keyframePoints(n, part)) {
        continue;
      }
      k.wX.insert(k.wX.end(), part.wX.begin(), part.wX.end());
      k.descriptors.insert(k.descriptors.end(), part.descriptors.begin(), part.descriptors.end());
    }
    if (k.wX.empty()) {
      continue;
    }
    m.relocalization->index(k);
    out.push_back(std::move(k));
  }
  return out;
}
} // namespace hslam
