/*
 * H-SLAM for ViSP.
 */
#include "tracking/TrackingReference.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! DSO makeCoarseDepthL0: a point's weight in the tracking reference is sqrt(1e-3 * H_idepth).
constexpr double kTrackingWeightScale = 1e-3;
//! Floor on a point's inverse-depth variance when turned into a tracking weight (a zero variance = unknown).
constexpr double kMinIdepthVariance = 1e-12;
} // namespace

void TrackingReference::clear()
{
  m_points.clear();
  m_features.clear();
  m_keyframe = -1;
}

void TrackingReference::build(const std::vector<KeyframePtr> &window)
{
  clear();
  if (window.empty()) {
    return;
  }
  const Keyframe &newest = *window.back();
  m_keyframe = newest.id();
  for (const KeyframePtr &host : window) {
    const SE3d refMhost = newest.frame->cMw * host->frame->cMw.inverse();
    for (const MapPoint &p : host->points) {
      if (p.status != PointStatus::active || !(p.idepth > 0.)) {
        continue;
      }
      const double weight = std::sqrt(kTrackingWeightScale / std::max(p.idepthVar, kMinIdepthVariance));
      CoarseTrackerPoint out;
      if (projectIntoReference(refMhost, m_K0, m_width, m_height, p.u, p.v, static_cast<float>(p.idepth),
                               static_cast<float>(weight), out)) {
        m_points.push_back(out);
      }
      if (p.hasOrb && p.isCorner && !p.depthFromPrior) {
        // Every active corner whose depth was measured, also one outside the reference image: the new frame may
        // see it (a guessed depth would place its 3D point wrong for the pose-only step). Gradient pixels
        // are left out: their descriptor is taken on an edge, where no FAST keypoint of the new frame sits at the
        // same place, so their matches bias the pose (share of matches kept by the pose-only step, fast preset:
        // 7-Scenes 56 % -> 73 %, Tsukuba 59 % -> 74 %, KITTI 72 % -> 83 % with corners only).
        ReferenceFeature f;
        const Eigen::Vector3d ray((p.u - m_K0.cx) / m_K0.fx, (p.v - m_K0.cy) / m_K0.fy, 1.);
        f.Xref = refMhost * (ray / p.idepth);
        f.orb = p.orb;
        f.angleDeg = p.orbAngleDeg;
        f.idepthVar = p.idepthVar;
        m_features.push_back(f);
      }
    }
  }
}

bool TrackingReference::applyTo(const std::vector<KeyframePtr> &window, CoarseTracker &tracker, int &keyframeId,
                                AffineBrightness &affine, double &exposure) const
{
  if (window.empty() || m_keyframe < 0) {
    return false;
  }
  KeyframePtr ref;
  for (const KeyframePtr &kf : window) {
    if (kf->id() == m_keyframe) {
      ref = kf;
    }
  }
  if (!ref) {
    return false;
  }
  tracker.setReference(*ref->frame, m_points);
  tracker.setReferenceFeatures(m_features);
  keyframeId = ref->id();
  affine = ref->frame->affine;
  exposure = ref->frame->exposure;
  return true;
}

void TrackingReference::fromStoredPoints(const GlobalMap &map, const std::vector<int> &keyframeIds, const SE3d &refMw,
                                         const PinholeIntrinsics &K0, int width, int height,
                                         std::vector<CoarseTrackerPoint> &points)
{
  points.clear();
  for (int id : keyframeIds) {
    const GlobalKeyframe *kf = map.find(id);
    if (!kf) {
      continue;
    }
    const SE3d refMhost = refMw * kf->cMw.inverse();
    for (const GlobalPoint &p : kf->points) {
      if (p.state != GlobalPointState::stored || !(p.idepth > 0.f)) {
        continue;
      }
      // The window's tracking weight (DSO: sqrt(1e-3 H_idepth)) from the variance kept at marginalisation.
      const double weight = std::sqrt(kTrackingWeightScale / std::max(static_cast<double>(p.idepthVar), 1e-12));
      CoarseTrackerPoint out;
      if (projectIntoReference(refMhost, K0, width, height, p.u, p.v, p.idepth, static_cast<float>(weight), out)) {
        points.push_back(out);
      }
    }
  }
}

void TrackingReference::storedFeatures(const GlobalMap &map, const std::vector<int> &keyframeIds,
                                       const PinholeIntrinsics &K0, std::vector<ReferenceFeature> &features)
{
  features.clear();
  for (int n : keyframeIds) {
    const GlobalKeyframe *kf = map.find(n);
    const SE3d wMc = kf->cMw.inverse();
    for (const GlobalPoint &p : kf->points) {
      if (!p.hasOrb || p.state != GlobalPointState::stored || !(p.idepth > 0.f)) {
        continue;
      }
      ReferenceFeature f;
      f.Xref = wMc * K0.unproject(p.u, p.v, p.idepth);
      f.orb = p.orb;
      f.angleDeg = p.orbAngleDeg;
      f.idepthVar = p.idepthVar;
      features.push_back(f);
    }
  }
}
} // namespace hslam
