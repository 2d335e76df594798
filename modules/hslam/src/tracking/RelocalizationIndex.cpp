/*
 * H-SLAM for ViSP.
 */
#include "tracking/RelocalizationIndex.h"

#include "common/HeapBytes.h"

namespace hslam
{
RelocalizationIndex::RelocalizationIndex(const OrbVocabulary &vocabulary)
    : m_vocabulary(vocabulary), m_database(vocabulary.wordCount())
{
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
