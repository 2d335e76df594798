/*
 * H-SLAM for ViSP.
 */
// LocalMapper's side of relocalisation: keyframe points in world coordinates, candidates for a lost frame, the
// memory descriptors add. See LocalMapper.h and tracking/RelocalizationIndex.h.
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include <algorithm>

namespace hslam
{
namespace
{
//! Relocalisation matches a lost frame against a candidate keyframe's points and those of the keyframes this many
//! ids before and after it.
constexpr int kRelocalizationNeighbours = 2;
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
    const Eigen::Vector3d ray((p.u - m.K0.cx) / m.K0.fx, (p.v - m.K0.cy) / m.K0.fy, 1.);
    out.wX.push_back(wMc * (ray / p.idepth));
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

bool LocalMapper::indexesKeyframes() const
{
  return m_impl->relocalization != nullptr;
}

std::vector<RelocalizationKeyframe> LocalMapper::relocalizationCandidates(RelocalizationFrame &frame,
                                                                          int maxCandidates) const
{
  const Impl &m = *m_impl;
  std::vector<RelocalizationKeyframe> out;
  if (!m.relocalization) {
    return out;
  }
  BowVector bow;
  m.relocalization->describeFrame(frame, bow);
  for (int id : m.relocalization->candidates(bow, maxCandidates)) {
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
