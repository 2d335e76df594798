/*
 * H-SLAM for ViSP.
 */
// LocalMapper, map file part: the map as a file holds it (vpHSlam::saveMap) and a loaded map made the global map
// (vpHSlam::loadMap). The file format is map/MapFile.h.
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace hslam
{
void LocalMapper::mapSnapshot(std::vector<GlobalKeyframe> &keyframes, std::vector<PosePoseEdge> &edges)
{
  Impl &m = *m_impl;
  keyframes.clear();
  edges = m_globalMap.posePoseEdges();
  for (const auto &entry : m_globalMap.keyframes()) {
    keyframes.push_back(entry.second);
  }
  const float minQuality = static_cast<float>(m.params.mapper.minTraceQuality);
  for (const KeyframePtr &kf : m_window) {
    keyframes.push_back(leanKeyframe(*kf, true));
    // The newest keyframes' points are mostly still immature: those whose depth interval has converged are kept too
    // (variance: the half interval squared), or the end of the run has no map to locate a camera in.
    for (const ImmaturePoint &pt : kf->immature) {
      if (!pt.hasOrb || !hasConvergedDepth(pt, minQuality)) {
        continue;
      }
      GlobalPoint q;
      q.u = pt.u;
      q.v = pt.v;
      q.idepth = 0.5f * (pt.idepthMin + pt.idepthMax);
      q.idepthVar = 0.25f * (pt.idepthMax - pt.idepthMin) * (pt.idepthMax - pt.idepthMin);
      q.orb = pt.orb;
      q.orbAngleDeg = pt.orbAngleDeg;
      q.isCorner = pt.isCorner;
      q.hasOrb = true;
      keyframes.back().points.push_back(std::move(q));
    }
    // Each window pair once: from the older keyframe to the newer one.
    std::vector<PairInformation> pairs = m.optimizer.pairInformation(kf->id());
    pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                               [&kf](const PairInformation &p) { return p.otherKeyframeId < kf->id(); }),
                pairs.end());
    for (const PosePoseEdge &e : posePoseEdges(*kf, pairs)) {
      if (e.to > e.from) { // a link back in time is the older window keyframe's link forward
        edges.push_back(e);
      }
    }
  }
  // In id order whatever left the window first: the same map always gives the same file.
  std::sort(keyframes.begin(), keyframes.end(),
            [](const GlobalKeyframe &a, const GlobalKeyframe &b) { return a.id < b.id; });
  // A segment whose window was dropped (tracking lost) leaves observers and edges naming keyframes nobody holds.
  std::set<int> held;
  for (const GlobalKeyframe &kf : keyframes) {
    held.insert(kf.id);
  }
  for (GlobalKeyframe &kf : keyframes) {
    for (GlobalPoint &p : kf.points) {
      dropObservers(p, [&held](int id) { return held.count(id) == 0; });
    }
  }
  edges.erase(std::remove_if(edges.begin(), edges.end(),
                             [&held](const PosePoseEdge &e) { return !held.count(e.from) || !held.count(e.to); }),
              edges.end());
}

void LocalMapper::restoreMap(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges)
{
  int lastSegment = -1;
  for (const GlobalKeyframe &kf : keyframes) {
    lastSegment = std::max(lastSegment, kf.segment);
  }
  m_globalMap.restore(std::move(keyframes), std::move(edges));
  if (m_impl->relocalization) {
    m_impl->relocalization->clear(); // a second load replaces the first: nothing of it stays searchable
  }
  m_segment = std::max(m_segment, lastSegment + 1);
}

void LocalMapper::reset()
{
  clear();
  m_globalMap.clear();
  m_reuse = ReuseStatistics();
  if (m_loop) {
    m_loop->statistics() = LoopStatistics();
  }
  m_segment = 0;
}
} // namespace hslam
