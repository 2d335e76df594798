/*
 * H-SLAM for ViSP.
 */
#include "tracking/RelocalizationIndex.h"

#include "common/HeapBytes.h"

#include <algorithm>

namespace hslam
{
namespace
{
//! Relocalisation matches a lost frame against a candidate keyframe's points and those of the keyframes this many
//! ids before and after it.
constexpr int kRelocalizationNeighbours = 2;
} // namespace

RelocalizationIndex::RelocalizationIndex(const OrbVocabulary &vocabulary, const PinholeIntrinsics &K0)
    : m_vocabulary(vocabulary), m_K0(K0), m_database(vocabulary.wordCount())
{
}

void RelocalizationIndex::addKeyframe(const Keyframe &kf)
{
  // The keyframe's bag-of-words vector: every selected point's descriptor (from its corners alone the synthetic
  // loop's loops were found less often; docs/hybrid-tracking.md).
  std::vector<OrbDescriptor> descriptors;
  descriptors.reserve(kf.immature.size());
  for (const ImmaturePoint &pt : kf.immature) {
    if (pt.hasOrb) {
      descriptors.push_back(pt.orb);
    }
  }
  addKeyframe(kf.id(), descriptors);
}

void RelocalizationIndex::storeKeyframe(const Keyframe &kf)
{
  RelocalizationKeyframe points;
  keyframePointsWorld(kf, points);
  setKeyframePoints(kf.id(), std::move(points.wX), std::move(points.descriptors));
}

// Corners only, as for tracking (gradient pixels' descriptors are not where a keypoint would be); measured on
// 7scenes_redkitchen_000-299 with frames 120-135 black: relocalised after 16 lost frames, 20 with every point.
void RelocalizationIndex::keyframePointsWorld(const Keyframe &kf, RelocalizationKeyframe &out) const
{
  out.id = kf.id();
  out.wX.clear();
  out.descriptors.clear();
  const SE3d wMc = kf.frame->cMw.inverse();
  for (const MapPoint &p : kf.points) {
    if (p.status == PointStatus::outlier || !p.hasOrb || !(p.idepth > 0.) || !p.isCorner) {
      continue;
    }
    out.wX.push_back(wMc * m_K0.unproject(p.u, p.v, p.idepth));
    out.descriptors.push_back(p.orb);
  }
}

void RelocalizationIndex::refreshKeyframe(const GlobalKeyframe &g)
{
  RelocalizationKeyframe points;
  if (!keyframePoints(g.id, points)) {
    return;
  }
  const SE3d wMc = g.cMw.inverse();
  points.wX.clear();
  points.descriptors.clear();
  for (const GlobalPoint &p : g.points) {
    if (p.hasOrb && p.isCorner && p.idepth > 0.f) {
      points.wX.push_back(wMc * m_K0.unproject(p.u, p.v, p.idepth));
      points.descriptors.push_back(p.orb);
    }
  }
  setKeyframePoints(g.id, std::move(points.wX), std::move(points.descriptors));
}

void RelocalizationIndex::indexGlobalMap(const GlobalMap &map)
{
  for (const auto &entry : map.keyframes()) {
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
        wX.push_back(wMc * m_K0.unproject(p.u, p.v, p.idepth));
        corners.push_back(p.orb);
      }
    }
    addKeyframe(kf.id, described);
    setKeyframePoints(kf.id, std::move(wX), std::move(corners));
  }
}

std::vector<RelocalizationKeyframe> RelocalizationIndex::candidatesFor(RelocalizationFrame &frame, int maxCandidates,
                                                                       int preferred,
                                                                       const std::vector<KeyframePtr> &window) const
{
  std::vector<RelocalizationKeyframe> out;
  BowVector bow;
  describeFrame(frame, bow);
  std::vector<int> ids = candidates(bow, maxCandidates);
  if (preferred >= 0 && std::find(ids.begin(), ids.end(), preferred) == ids.end()) {
    ids.insert(ids.begin(), preferred); // the caller's guess (the keyframe that placed the previous frame) first
  }
  for (int id : ids) {
    // The candidate and its neighbours in time (they see the same place; a keyframe alone hosts few points).
    RelocalizationKeyframe k;
    k.id = id;
    for (int n = id - kRelocalizationNeighbours; n <= id + kRelocalizationNeighbours; ++n) {
      RelocalizationKeyframe part;
      auto inWindow = std::find_if(window.begin(), window.end(), [n](const KeyframePtr &w) { return w->id() == n; });
      if (inWindow != window.end()) {
        keyframePointsWorld(**inWindow, part);
      } else if (!keyframePoints(n, part)) {
        continue;
      }
      k.wX.insert(k.wX.end(), part.wX.begin(), part.wX.end());
      k.descriptors.insert(k.descriptors.end(), part.descriptors.begin(), part.descriptors.end());
    }
    if (k.wX.empty()) {
      continue;
    }
    index(k);
    out.push_back(std::move(k));
  }
  return out;
}

void RelocalizationIndex::addKeyframe(int id, const std::vector<OrbDescriptor> &descriptors)
{
  if (descriptors.empty()) {
    return;
  }
  BowVector bow;
  m_vocabulary.transform(descriptors, bow);
  m_database.add(id, bow);
}

void RelocalizationIndex::setKeyframePoints(int id, std::vector<Eigen::Vector3d> wX,
                                            std::vector<OrbDescriptor> descriptors)
{
  RelocalizationKeyframe &k = m_points[id];
  k.id = id;
  k.wX = std::move(wX);
  k.descriptors = std::move(descriptors);
  k.direct.clear(); // indexed when a query needs it
}

bool RelocalizationIndex::keyframePoints(int id, RelocalizationKeyframe &out) const
{
  const auto it = m_points.find(id);
  if (it == m_points.end()) {
    return false;
  }
  out = it->second;
  return true;
}

void RelocalizationIndex::index(RelocalizationKeyframe &keyframe) const
{
  BowVector unused;
  keyframe.direct.clear();
  if (!keyframe.descriptors.empty()) {
    m_vocabulary.transform(keyframe.descriptors, unused, keyframe.direct, kDirectIndexLevelsUp);
  }
}

void RelocalizationIndex::describeFrame(RelocalizationFrame &frame, BowVector &bow) const
{
  bow.clear();
  frame.direct.clear();
  if (!frame.descriptors.empty()) {
    m_vocabulary.transform(frame.descriptors, bow, frame.direct, kDirectIndexLevelsUp);
  }
}

std::vector<int> RelocalizationIndex::candidates(const BowVector &bow, int maxCandidates) const
{
  std::vector<int> ids;
  if (bow.empty() || m_database.size() == 0) {
    return ids;
  }
  const std::vector<KeyframeDatabase::Candidate> found = m_database.query(bow, KeyframeDatabase::Query());
  for (const KeyframeDatabase::Candidate &c : found) {
    if (static_cast<int>(ids.size()) >= maxCandidates) {
      break;
    }
    ids.push_back(c.id);
  }
  return ids;
}

void RelocalizationIndex::removeKeyframe(int id)
{
  m_database.remove(id);
  m_points.erase(id);
}

void RelocalizationIndex::clear()
{
  m_database.clear();
  m_points.clear();
}

double RelocalizationIndex::memoryBytes() const
{
  // Every block held, allocator overhead included (common/HeapBytes.h).
  // The stored keyframes' direct indices stay empty (index() fills the caller's copy).
  double bytes = m_database.memoryBytes() + mapNodesHeapBytes(m_points);
  for (const auto &entry : m_points) {
    bytes += vectorHeapBytes(entry.second.wX) + vectorHeapBytes(entry.second.descriptors);
  }
  return bytes;
}
} // namespace hslam
