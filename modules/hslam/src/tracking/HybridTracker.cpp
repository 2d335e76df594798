/*
 * H-SLAM for ViSP.
 */
#include "tracking/HybridTracker.h"

#include "features/CornerDetector.h"
#include "tracking/PoseOnlyOptimizer.h"
#include "tracking/Relocalizer.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! The radius is doubled once when too few points match (ORB-SLAM2 TrackWithMotionModel).
constexpr float kWidenFactor = 2.f;
//! Projected points closer than this to the new camera are not matched, scene units.
constexpr double kMinDepth = 1e-6;
} // namespace

HybridTracker::HybridTracker(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height)
    : m_params(params.tracking), m_cornerMinDistance(params.features.cornerMinDistance), m_K0(K0), m_width(width),
      m_height(height)
{
}

void HybridTracker::extract(const vpImage<unsigned char> &raw)
{
  CornerOptions options;
  options.threshold = m_params.frameFastThreshold;
  options.maxCorners = m_params.frameFeatures;
  options.minDistance = m_cornerMinDistance;
  options.border = kOrbBorderPx + 1;
  detectCorners(raw, options, m_pixels, nullptr, &m_cornerHint);
  m_descriptors.compute(raw, m_pixels, m_desc, m_valid, &m_angles);
  m_keypoints.clear();
  m_keypoints.reserve(m_pixels.size());
  for (size_t i = 0; i < m_pixels.size(); ++i) {
    if (!m_valid[i]) {
      continue;
    }
    FrameKeypoint k;
    k.u = m_pixels[i].x;
    k.v = m_pixels[i].y;
    k.angleDeg = m_angles[i];
    k.descriptor = m_desc[i];
    m_keypoints.push_back(k);
  }
}

void HybridTracker::project(const std::vector<ReferenceFeature> &features, const SE3d &newMref)
{
  m_projected.clear();
  m_projectedFeature.clear();
  const Eigen::Matrix3d R = newMref.rotationMatrix();
  const Eigen::Vector3d t = newMref.translation();
  for (size_t i = 0; i < features.size(); ++i) {
    const Eigen::Vector3d X = R * features[i].Xref + t;
    if (!(X.z() > kMinDepth)) {
      continue;
    }
    const double u = m_K0.fx * X.x() / X.z() + m_K0.cx;
    const double v = m_K0.fy * X.y() / X.z() + m_K0.cy;
    if (!(u >= 0. && v >= 0. && u <= m_width - 1. && v <= m_height - 1.)) {
      continue;
    }
    ProjectedPoint p;
    p.u = static_cast<float>(u);
    p.v = static_cast<float>(v);
    p.angleDeg = features[i].angleDeg;
    p.descriptor = features[i].orb;
    m_projected.push_back(p);
    m_projectedFeature.push_back(static_cast<int>(i));
  }
}

RelocalizationFrame HybridTracker::relocalizationFrame() const
{
  RelocalizationFrame frame;
  frame.uv.reserve(m_keypoints.size());
  frame.descriptors.reserve(m_keypoints.size());
  for (const FrameKeypoint &k : m_keypoints) {
    frame.uv.emplace_back(k.u, k.v);
    frame.descriptors.push_back(k.descriptor);
  }
  return frame;
}

bool HybridTracker::recoverFromLargeMotion(const std::vector<ReferenceFeature> &features, SE3d &newMref) const
{
  // The reference's corners against every keypoint (no prediction), then PnP RANSAC and the pose-only refinement:
  // the relocaliser's machinery with the tracking reference as the only candidate.
  RelocalizationKeyframe reference;
  reference.wX.reserve(features.size());
  reference.descriptors.reserve(features.size());
  for (const ReferenceFeature &f : features) {
    reference.wX.push_back(f.Xref);
    reference.descriptors.push_back(f.orb);
  }
  const RelocalizationFrame frame = relocalizationFrame();
  RelocalizerOptions options;
  options.minMatches = m_params.minMatchesBeforeWidening;
  options.minInliers = m_params.minMatchesBeforeWidening;
  const RelocalizationResult r = relocalize(frame, {&reference}, m_K0, options);
  if (!r.success) {
    return false;
  }
  newMref = r.cTw;
  return true;
}

void HybridTracker::weighByDepthVariance(const std::vector<ReprojectionObservation> &observations,
                                         const std::vector<double> &idepthVars, const PoseOnlyResult &pose,
                                         GeometricTerm &term) const
{
  // Paper eq. 3: w_i = (1 / var_i) / max_j (1 / var_j) over the inliers. A point of unknown variance (a stored
  // point without one) leaves every weight at 1: one scale for all or none.
  std::vector<double> information;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (!pose.inlier[i]) {
      continue;
    }
    if (!(idepthVars[i] > 0.) || !std::isfinite(idepthVars[i])) {
      return;
    }
    information.push_back(1. / idepthVars[i]);
  }
  if (information.empty()) {
    return;
  }
  const double maxInformation = *std::max_element(information.begin(), information.end());
  term.weights.clear();
  double sumWeights = 0., sumWeightedError2 = 0.;
  size_t j = 0;
  for (size_t i = 0; i < observations.size(); ++i) {
    if (!pose.inlier[i]) {
      continue;
    }
    const double w = information[j++] / maxInformation;
    term.weights.push_back(w);
    Eigen::Vector2d r;
    if (reprojectionResidual(pose.cTw, observations[i], m_K0, kMinDepth, r)) {
      sumWeights += w;
      sumWeightedError2 += w * r.squaredNorm();
    }
  }
  // n_g s_g^2 of eq. 1 from the weighted residuals: the term keeps its balance against the photometric one (with the
  // plain count and variance it shrank by the mean weight).
  if (sumWeights > 0.) {
    term.count = sumWeights;
    term.sigma2Px = sumWeightedError2 / sumWeights;
  }
}

bool HybridTracker::indirectStep(const std::vector<ReferenceFeature> &features, const SE3d &predictedMref,
                                 IndirectStepResult &out)
{
  out = IndirectStepResult();
  out.newMref = predictedMref;
  project(features, predictedMref);
  if (m_projected.empty() || m_keypoints.empty()) {
    return false;
  }
  OrbMatcherOptions options;
  options.radiusPx = static_cast<float>(m_params.matchRadiusPx);
  options.maxDistance = m_params.matchMaxDistance;
  options.ratio = static_cast<float>(m_params.matchRatio);
  const OrbMatcher matcher(m_keypoints, m_width, m_height, options);
  std::vector<OrbMatch> matches = matcher.matchProjected(m_projected);
  if (static_cast<int>(matches.size()) < m_params.minMatchesBeforeWidening) {
    std::vector<OrbMatch> wider = matcher.matchProjected(m_projected, kWidenFactor * options.radiusPx);
    if (wider.size() > matches.size()) {
      matches.swap(wider);
    }
  }
  out.matches = static_cast<int>(matches.size());
  SE3d start = predictedMref;
  if (out.matches < m_params.minMatchesBeforeWidening && recoverFromLargeMotion(features, start)) {
    // The prediction was too far off for a search around it (fast motion, skipped frames): matching without a
    // prediction gave a pose; the guided search is run again around it.
    out.recovered = true;
    out.newMref = start;
    project(features, start);
    matches = matcher.matchProjected(m_projected); // indices refer to the new projection
    out.matches = static_cast<int>(matches.size());
  }
  if (out.matches < m_params.minGeometricInliers) {
    return false;
  }
  std::vector<ReprojectionObservation> observations(matches.size());
  std::vector<double> idepthVars(matches.size());
  for (size_t i = 0; i < matches.size(); ++i) {
    const FrameKeypoint &k = m_keypoints[static_cast<size_t>(matches[i].keypoint)];
    const ReferenceFeature &f =
        features[static_cast<size_t>(m_projectedFeature[static_cast<size_t>(matches[i].point)])];
    observations[i].wX = f.Xref;
    observations[i].uv = Eigen::Vector2d(k.u, k.v);
    idepthVars[i] = f.idepthVar;
  }
  const PoseOnlyResult pose = optimizePoseOnly(start, observations, m_K0);
  out.inliers = pose.inliers;
  if (pose.inliers < m_params.minGeometricInliers || !pose.cTw.translation().allFinite()) {
    return false;
  }
  out.newMref = pose.cTw;
  out.term.Xref.reserve(static_cast<size_t>(pose.inliers));
  out.term.uv.reserve(static_cast<size_t>(pose.inliers));
  for (size_t i = 0; i < observations.size(); ++i) {
    if (pose.inlier[i]) {
      out.term.Xref.push_back(observations[i].wX);
      out.term.uv.push_back(observations[i].uv);
    }
  }
  out.term.inliers = pose.inliers;
  out.term.sigma2Px = pose.inlierRmsePx * pose.inlierRmsePx;
  if (m_params.geometricDepthWeights) {
    weighByDepthVariance(observations, idepthVars, pose, out.term);
  }
  out.usable = true;
  return true;
}
} // namespace hslam
