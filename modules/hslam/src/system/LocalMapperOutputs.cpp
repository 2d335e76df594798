/*
 * H-SLAM for ViSP.
 */
// LocalMapper's outputs and queries: the tracking reference, keyframe states, points and counts, memory, map files,
// relocalisation (LocalMapper.h). Each is answered by the component that owns the state.
#include "system/LocalMapper.h"

#include "features/BinaryDescriptor.h"
#include "tracking/CoarseTracker.h"
#include "tracking/RelocalizationIndex.h"
#include "tracking/WindowRelocalization.h"

namespace hslam
{
bool LocalMapper::prepareTrackingReference(CoarseTracker &tracker, int &keyframeId, AffineBrightness &affine,
                                           double &exposure) const
{
  return m_reference.applyTo(m_window->keyframes(), tracker, keyframeId, affine, exposure);
}

void LocalMapper::takeKeyframeStates(std::vector<KeyframeState> &states)
{
  states = m_marginalizedStates;
  m_marginalizedStates.clear();
  for (const KeyframePtr &kf : m_window->keyframes()) {
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
  m_window->pointsWorld(points, nullptr, true);
}

void LocalMapper::mapPointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> &status) const
{
  points.clear();
  status.clear();
  m_window->pointsWorld(points, &status, false);
  m_keeper.pointsWorld(points, status);
}

int LocalMapper::activePointCount() const
{
  return m_window->activePointCount();
}

int LocalMapper::immaturePointCount() const
{
  return m_window->immaturePointCount();
}

double LocalMapper::windowMemoryBytes() const
{
  return m_window->memoryBytes();
}

double LocalMapper::marginalizedMemoryBytes(bool exact)
{
  constexpr size_t kRecountEvery = 50; // a count is redone after a change of 1 / 50 of the stored keyframes
  const size_t stored = m_keeper.globalMap().keyframes().size();
  const size_t changed =
      stored > m_countedStoredKeyframes ? stored - m_countedStoredKeyframes : m_countedStoredKeyframes - stored;
  if (exact || !m_marginalizedCounted || changed * kRecountEvery >= std::max<size_t>(m_countedStoredKeyframes, 1)) {
    double bytes = m_keeper.memoryBytes() + loopMemoryBytes();
    m_countedRelocalizationBytesPerKeyframe = 0.;
    if (m_relocalization) {
      const double relocalization = m_relocalization->memoryBytes();
      bytes += relocalization;
      m_countedRelocalizationBytesPerKeyframe =
          m_relocalization->size() > 0 ? relocalization / static_cast<double>(m_relocalization->size()) : 0.;
    }
    m_countedMarginalizedBytes = bytes;
    m_countedStoredKeyframes = stored;
    m_marginalizedCounted = true;
    return bytes;
  }
  // Here a count of no stored keyframe means none is stored now either (any change forces a count).
  return m_countedStoredKeyframes == 0
             ? m_countedMarginalizedBytes
             : m_countedMarginalizedBytes * static_cast<double>(stored) / static_cast<double>(m_countedStoredKeyframes);
}

SE3d LocalMapper::newestKeyframe_cMw() const
{
  return m_window->empty() ? SE3d() : m_window->keyframes().back()->frame->cMw;
}

int LocalMapper::newestKeyframeId() const
{
  return m_window->empty() ? -1 : m_window->keyframes().back()->id();
}

// ------------------------------------------------------------------------------------------------ global map

LocalMapper::ReuseStatistics LocalMapper::reuseStatistics() const
{
  return m_keeper.statistics(m_window->keyframes());
}

bool LocalMapper::keepsGlobalMap() const
{
  return keepsGlobalMap(m_params.system.mode);
}

LocalMapper::LoopStatistics LocalMapper::loopStatistics() const
{
  return m_loop ? m_loop->statistics() : LoopStatistics();
}

double LocalMapper::loopMemoryBytes() const
{
  return m_loop ? m_loop->memoryBytes() : 0.;
}

void LocalMapper::mapSnapshot(std::vector<GlobalKeyframe> &keyframes, std::vector<PosePoseEdge> &edges)
{
  KeyframeWindow &window = *m_window;
  m_keeper.snapshot(
      window.keyframes(), [&window](int id) { return window.pairInformation(id); }, keyframes, edges);
}

void LocalMapper::restoreMap(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges)
{
  m_keeper.restore(std::move(keyframes), std::move(edges));
  m_marginalizedCounted = false;
  if (m_relocalization) {
    m_relocalization->clear(); // a second load replaces the first: nothing of it stays searchable
  }
}

// ------------------------------------------------------------------------------------------------ relocalisation

double LocalMapper::descriptorBytesPerKeyframe() const
{
  if (!m_window->withDescriptors() || m_window->empty()) {
    return 0.;
  }
  // What a descriptor adds to a point: the descriptor, its angle and its flag (padding included by sizeof
  // differences would overstate it; these are the members added for descriptor sharing).
  constexpr double kPerPoint = sizeof(OrbDescriptor) + sizeof(float) + sizeof(bool);
  double points = 0.;
  for (const KeyframePtr &kf : m_window->keyframes()) {
    points += static_cast<double>(kf->points.size() + kf->immature.size());
  }
  // The relocalisation index's share as of the last count of marginalizedMemoryBytes() (walking it is O(map)).
  return kPerPoint * points / static_cast<double>(m_window->size()) + m_countedRelocalizationBytesPerKeyframe;
}

bool LocalMapper::indexesKeyframes() const
{
  return m_relocalization != nullptr;
}

bool LocalMapper::indexGlobalMap()
{
  if (!m_relocalization) {
    return false;
  }
  m_relocalization->indexGlobalMap(m_keeper.globalMap());
  return true;
}

std::vector<RelocalizationKeyframe> LocalMapper::relocalizationCandidates(RelocalizationFrame &frame, int maxCandidates,
                                                                          int preferred) const
{
  if (!m_relocalization) {
    return {};
  }
  return m_relocalization->candidatesFor(frame, maxCandidates, preferred, m_window->keyframes());
}

std::vector<WindowView> LocalMapper::windowViews() const
{
  std::vector<WindowView> views;
  for (const KeyframePtr &kf : m_window->keyframes()) {
    WindowView v;
    v.id = kf->id();
    v.cMw = kf->frame->cMw;
    v.frame = kf->frame;
    views.push_back(std::move(v));
  }
  return views;
}

void LocalMapper::localMapFeatures(int id, std::vector<ReferenceFeature> &features, std::vector<int> &keyframeIds) const
{
  keyframeIds = m_keeper.storedNeighbourhood(id);
  TrackingReference::storedFeatures(m_keeper.globalMap(), keyframeIds, m_K0, features);
}

void LocalMapper::localMapReference(const std::vector<int> &keyframeIds, const SE3d &refMw,
                                    std::vector<CoarseTrackerPoint> &points) const
{
  TrackingReference::fromStoredPoints(m_keeper.globalMap(), keyframeIds, refMw, m_K0, m_width, m_height, points);
}

int LocalMapper::closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) const
{
  return m_keeper.closestKeyframe(cMw, keyframeIds);
}
} // namespace hslam
