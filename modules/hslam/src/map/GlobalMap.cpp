/*
 * H-SLAM for ViSP.
 */
#include "map/GlobalMap.h"

#include "common/HeapBytes.h"

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <limits>

namespace hslam
{
void GlobalMap::clear()
{
  m_keyframes.clear();
  m_shared.clear();
  m_posePose.clear();
  m_culled = 0;
  m_pointCount = 0;
}

void GlobalMap::countShared(const GlobalPoint &p, int host, int sign)
{
  // The set of keyframes seeing the point: its host and its observers; every pair of them shares it.
  const size_t n = p.observers.size();
  for (size_t i = 0; i <= n; ++i) {
    const int a = i == n ? host : p.observers[i];
    for (size_t j = i + 1; j <= n; ++j) {
      const int b = j == n ? host : p.observers[j];
      if (a == b) {
        continue;
      }
      m_shared[a][b] += sign;
      m_shared[b][a] += sign;
    }
  }
}

GlobalKeyframe &GlobalMap::store(GlobalKeyframe keyframe)
{
  const int id = keyframe.id;
  const auto before = m_keyframes.find(id);
  m_pointCount -= before == m_keyframes.end() ? 0 : before->second.points.size();
  GlobalKeyframe &kf = m_keyframes[id] = std::move(keyframe);
  kf.revision = m_nextRevision++;
  m_pointCount += kf.points.size();
  for (const GlobalPoint &p : kf.points) {
    if (p.state == GlobalPointState::stored) {
      countShared(p, id, +1);
    }
  }
  return kf;
}

bool GlobalMap::add(GlobalKeyframe keyframe)
{
  return applyCulling(store(std::move(keyframe)).id);
}

void GlobalMap::restore(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges)
{
  clear();
  for (GlobalKeyframe &keyframe : keyframes) {
    m_culled += store(std::move(keyframe)).culled ? 1 : 0;
  }
  m_posePose = std::move(edges);
}

GlobalMap GlobalMap::graphCopy() const
{
  GlobalMap copy(m_options);
  for (const auto &entry : m_keyframes) {
    const GlobalKeyframe &kf = entry.second;
    GlobalKeyframe header;
    header.id = kf.id;
    header.frameId = kf.frameId;
    header.segment = kf.segment;
    header.timestamp = kf.timestamp;
    header.exposure = kf.exposure;
    header.cMw = kf.cMw;
    header.affine = kf.affine;
    header.culled = kf.culled;
    copy.m_keyframes.emplace_hint(copy.m_keyframes.end(), entry.first, std::move(header));
  }
  copy.m_shared = m_shared;
  copy.m_posePose = m_posePose;
  copy.m_culled = m_culled;
  return copy;
}

void GlobalMap::addPosePoseEdge(const PosePoseEdge &edge)
{
  m_posePose.push_back(edge);
}

void GlobalMap::absorb(int keyframeId, size_t pointIndex, GlobalPointState state)
{
  GlobalKeyframe *kf = findForChange(keyframeId);
  if (!kf || pointIndex >= kf->points.size() || kf->points[pointIndex].state != GlobalPointState::stored) {
    return;
  }
  GlobalPoint &p = kf->points[pointIndex];
  countShared(p, keyframeId, -1);
  p.state = state;
  // The active point carries the observers on; this copy keeps only what history needs.
  std::vector<int>().swap(p.observers);
  std::vector<std::array<float, 2>>().swap(p.observedAt);
}

void GlobalMap::addObservation(int keyframeId, size_t pointIndex, int observerId, float u, float v)
{
  GlobalKeyframe *kf = findKeepingRevision(keyframeId);
  if (!kf || pointIndex >= kf->points.size() || observerId == keyframeId) {
    return;
  }
  GlobalPoint &p = kf->points[pointIndex];
  auto at = std::lower_bound(p.observers.begin(), p.observers.end(), observerId);
  if (p.state != GlobalPointState::stored || (at != p.observers.end() && *at == observerId)) {
    return;
  }
  const size_t index = static_cast<size_t>(at - p.observers.begin());
  countShared(p, keyframeId, -1);
  const float unknown = std::numeric_limits<float>::quiet_NaN();
  p.observedAt.resize(p.observers.size(), {unknown, unknown});
  p.observers.insert(at, observerId);
  p.observedAt.insert(p.observedAt.begin() + static_cast<std::ptrdiff_t>(index), {u, v});
  countShared(p, keyframeId, +1);
}

GlobalKeyframe *GlobalMap::findForChange(int id)
{
  auto it = m_keyframes.find(id);
  if (it == m_keyframes.end()) {
    return nullptr;
  }
  it->second.revision = m_nextRevision++;
  return &it->second;
}

GlobalKeyframe *GlobalMap::findKeepingRevision(int id)
{
  auto it = m_keyframes.find(id);
  return it == m_keyframes.end() ? nullptr : &it->second;
}

const GlobalKeyframe *GlobalMap::find(int id) const
{
  auto it = m_keyframes.find(id);
  return it == m_keyframes.end() ? nullptr : &it->second;
}

std::vector<CovisibilityEdge> GlobalMap::covisibilityEdges() const
{
  std::vector<CovisibilityEdge> out;
  for (const auto &row : m_shared) {
    for (const auto &e : row.second) {
      if (row.first >= e.first || e.second < m_options.covisibilityMinShared) {
        continue; // each edge once (a < b)
      }
      if (isCulled(row.first) || isCulled(e.first)) {
        continue;
      }
      CovisibilityEdge edge;
      edge.a = row.first;
      edge.b = e.first;
      edge.weight = e.second;
      out.push_back(edge);
    }
  }
  return out;
}

std::vector<int> GlobalMap::covisibleWith(int id, size_t maxCount) const
{
  std::vector<int> out;
  auto row = m_shared.find(id);
  if (row == m_shared.end() || isCulled(id)) {
    return out;
  }
  for (const auto &e : row->second) {
    if (out.size() >= maxCount) {
      break;
    }
    if (e.second >= m_options.covisibilityMinShared && !isCulled(e.first)) {
      out.push_back(e.first);
    }
  }
  return out;
}

bool GlobalMap::isCulled(int id) const
{
  const GlobalKeyframe *kf = find(id);
  return kf && kf->culled;
}

bool GlobalMap::applyCulling(int id)
{
  GlobalKeyframe *kf = findKeepingRevision(id);
  if (!kf || kf->culled) {
    return false;
  }
  size_t considered = 0, redundant = 0;
  for (const GlobalPoint &p : kf->points) {
    if (p.state != GlobalPointState::stored) {
      continue;
    }
    ++considered;
    // Observers from the host's own window do not count (see GlobalMap.h); observers that were culled themselves
    // no longer count either (ORB-SLAM erases a culled keyframe's observations).
    int observers = 0;
    for (int o : p.observers) {
      const GlobalKeyframe *other = find(o);
      observers += (std::abs(o - id) > m_options.windowSize && (!other || !other->culled)) ? 1 : 0;
    }
    redundant += observers >= m_options.cullMinObservers ? 1u : 0u;
  }
  if (considered == 0 || static_cast<double>(redundant) <= m_options.cullObservedShare * considered) {
    return false;
  }
  kf->culled = true;
  ++m_culled;
  return true;
}

double GlobalMap::memoryBytes() const
{
  // Every block the map holds, allocator overhead included (common/HeapBytes.h).
  double bytes = mapNodesHeapBytes(m_keyframes);
  for (const auto &k : m_keyframes) {
    bytes += vectorHeapBytes(k.second.points);
    for (const GlobalPoint &p : k.second.points) {
      bytes += vectorHeapBytes(p.observers) + vectorHeapBytes(p.observedAt);
    }
  }
  bytes += mapNodesHeapBytes(m_shared);
  for (const auto &row : m_shared) {
    bytes += mapNodesHeapBytes(row.second);
  }
  return bytes + vectorHeapBytes(m_posePose);
}
bool GlobalMap::applySimilarity(int id, const Sim3d &Siw)
{
  GlobalKeyframe *g = findForChange(id);
  if (!g) {
    return false;
  }
  const double s = Siw.scale();
  g->cMw = SE3d(Siw.unitQuaternion(), Siw.translation() / s);
  for (GlobalPoint &p : g->points) {
    p.idepth = static_cast<float>(p.idepth * s);
    p.idepthVar = static_cast<float>(p.idepthVar * s * s);
  }
  return true;
}
} // namespace hslam
