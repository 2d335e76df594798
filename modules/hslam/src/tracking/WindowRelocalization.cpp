/*
 * H-SLAM for ViSP.
 */
#include "tracking/WindowRelocalization.h"

#include "mapping/TwoViewGeometry.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! Chi-square 95 % bounds for 1 and 2 degrees of freedom (ORB-SLAM2's epipolar and reprojection tests).
constexpr double kChi2OneDof = 3.841;
constexpr double kChi2TwoDof = 5.991;
constexpr double kPi = 3.14159265358979323846;
//! Larger than any Hamming distance of 256-bit descriptors.
constexpr int kNoDistance = 257;

//! Squared reprojection error of the camera-frame point \e X at pixel \e uv.
double reprojectionErrorSq(const Eigen::Vector3d &X, const Eigen::Vector2d &uv, const PinholeIntrinsics &K)
{
  const double u = K.fx * X.x() / X.z() + K.cx;
  const double v = K.fy * X.y() / X.z() + K.cy;
  return (u - uv.x()) * (u - uv.x()) + (v - uv.y()) * (v - uv.y());
}

Eigen::Vector2d normalised(const Eigen::Vector2d &uv, const PinholeIntrinsics &K)
{
  return Eigen::Vector2d((uv.x() - K.cx) / K.fx, (uv.y() - K.cy) / K.fy);
}

//! F = K^-T [t]x R K^-1: pixels of b on the epipolar line of a pixel of a satisfy x_b^T F x_a = 0 (X_b = R X_a + t).
Eigen::Matrix3d fundamentalMatrix(const Eigen::Matrix3d &R, const Eigen::Vector3d &t, const PinholeIntrinsics &K)
{
  Eigen::Matrix3d tx;
  tx << 0., -t.z(), t.y(), t.z(), 0., -t.x(), -t.y(), t.x(), 0.;
  Eigen::Matrix3d Kinv;
  Kinv << 1. / K.fx, 0., -K.cx / K.fx, 0., 1. / K.fy, -K.cy / K.fy, 0., 0., 1.;
  return Kinv.transpose() * tx * R * Kinv;
}

/*!
  Best keypoint of b (of the first \e nb) for each free keypoint of a (of the first \e na) within the epipolar band,
  then one keypoint of a per keypoint of b (the closest descriptor): per keypoint of b, its match in a or -1.
*/
std::vector<int> epipolarMatches(const DescribedView &a, std::size_t na, const DescribedView &b, std::size_t nb,
                                 const Eigen::Matrix3d &F, const ViewTriangulationOptions &options,
                                 const std::vector<unsigned char> &done)
{
  std::vector<int> matchOfB(nb, -1), distanceOfB(nb, kNoDistance);
  for (std::size_t i = 0; i < na; ++i) {
    if (done[i]) {
      continue;
    }
    const Eigen::Vector3d line = F * Eigen::Vector3d(a.uv[i].x(), a.uv[i].y(), 1.);
    const double norm2 = line.x() * line.x() + line.y() * line.y();
    if (!(norm2 > 0.)) {
      continue;
    }
    int best = kNoDistance, second = kNoDistance, bestIndex = -1;
    for (std::size_t j = 0; j < nb; ++j) {
      const double d = line.x() * b.uv[j].x() + line.y() * b.uv[j].y() + line.z();
      const double sigma = options.epipolarSigmaPx * static_cast<double>(b.scale[j]);
      if (d * d > kChi2OneDof * sigma * sigma * norm2) {
        continue;
      }
      const int distance = hammingDistance(a.descriptors[i], b.descriptors[j]);
      if (distance < best) {
        second = best;
        best = distance;
        bestIndex = static_cast<int>(j);
      } else if (distance < second) {
        second = distance;
      }
    }
    if (bestIndex < 0 || best > options.maxDistance ||
        !(static_cast<float>(best) < options.ratio * static_cast<float>(second))) {
      continue;
    }
    const std::size_t j = static_cast<std::size_t>(bestIndex);
    if (best < distanceOfB[j]) {
      matchOfB[j] = static_cast<int>(i);
      distanceOfB[j] = best;
    }
  }
  return matchOfB;
}

//! The two views' relative motion (X_b = R X_a + t) and what the triangulation of their matches needs.
struct ViewPair {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  Eigen::Matrix3d Rwa, Rwb; //!< rotations of the views' rays into the world
  double minCosParallax;
};

//! Keypoint i of a and j of b triangulated into \e Xa (camera a): false with too little parallax, behind a camera,
//! or reprojected too far from either keypoint.
bool triangulateMatch(const DescribedView &a, std::size_t i, const DescribedView &b, std::size_t j,
                      const ViewPair &pair, const PinholeIntrinsics &K, const ViewTriangulationOptions &options,
                      Eigen::Vector3d &Xa)
{
  const Eigen::Vector2d xa = normalised(a.uv[i], K);
  const Eigen::Vector2d xb = normalised(b.uv[j], K);
  const Eigen::Vector3d rayA = pair.Rwa * Eigen::Vector3d(xa.x(), xa.y(), 1.);
  const Eigen::Vector3d rayB = pair.Rwb * Eigen::Vector3d(xb.x(), xb.y(), 1.);
  if (rayA.dot(rayB) / (rayA.norm() * rayB.norm()) > pair.minCosParallax) {
    return false; // too little parallax for a depth
  }
  if (!triangulateLinear(xa, xb, pair.R, pair.t, Xa)) {
    return false;
  }
  const Eigen::Vector3d Xb = pair.R * Xa + pair.t;
  if (!(Xa.z() > 0.) || !(Xb.z() > 0.)) {
    return false;
  }
  const double sa = options.reprojectionSigmaPx * static_cast<double>(a.scale[i]);
  const double sb = options.reprojectionSigmaPx * static_cast<double>(b.scale[j]);
  return !(reprojectionErrorSq(Xa, a.uv[i], K) > kChi2TwoDof * sa * sa ||
           reprojectionErrorSq(Xb, b.uv[j], K) > kChi2TwoDof * sb * sb);
}
} // namespace

int triangulateViews(const DescribedView &a, const DescribedView &b, const PinholeIntrinsics &K,
                     const ViewTriangulationOptions &options, std::vector<unsigned char> &done,
                     std::vector<Eigen::Vector3d> &wX, std::vector<OrbDescriptor> &descriptors)
{
  const std::size_t na = std::min(a.uv.size(), std::min(a.descriptors.size(), a.scale.size()));
  const std::size_t nb = std::min(b.uv.size(), std::min(b.descriptors.size(), b.scale.size()));
  done.resize(a.uv.size(), 0);
  if (na == 0 || nb == 0) {
    return 0;
  }
  const SE3d bMa = b.cMw * a.cMw.inverse();
  ViewPair pair;
  pair.R = bMa.rotationMatrix();
  pair.t = bMa.translation();
  if (!(pair.t.norm() > 0.)) {
    return 0; // no baseline: nothing to triangulate
  }
  const Eigen::Matrix3d F = fundamentalMatrix(pair.R, pair.t, K);
  pair.minCosParallax = std::cos(options.minParallaxDeg * kPi / 180.);
  pair.Rwa = a.cMw.inverse().rotationMatrix();
  pair.Rwb = b.cMw.inverse().rotationMatrix();
  const SE3d wMa = a.cMw.inverse();

  const std::vector<int> matchOfB = epipolarMatches(a, na, b, nb, F, options, done);
  int added = 0;
  for (std::size_t j = 0; j < nb; ++j) {
    if (matchOfB[j] < 0) {
      continue;
    }
    const std::size_t i = static_cast<std::size_t>(matchOfB[j]);
    Eigen::Vector3d Xa;
    if (!triangulateMatch(a, i, b, j, pair, K, options, Xa)) {
      continue;
    }
    wX.push_back(wMa * Xa);
    descriptors.push_back(a.descriptors[i]);
    done[i] = 1;
    ++added;
  }
  return added;
}

WindowRelocalization::WindowRelocalization(const PinholeIntrinsics &K, const WindowRelocalizationOptions &options)
    : m_K(K), m_options(options), m_extractor(options.orb)
{
}

void WindowRelocalization::extract(const vpImage<unsigned char> &raw, std::vector<Eigen::Vector2d> &uv,
                                   std::vector<float> &scale, std::vector<OrbDescriptor> &descriptors)
{
  uv.clear();
  scale.clear();
  descriptors.clear();
  if (raw.getSize() == 0) {
    return;
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat rows;
  m_extractor.extract(raw, keypoints, rows);
  descriptors = descriptorsFromMat(rows);
  const std::size_t n = std::min(keypoints.size(), descriptors.size());
  descriptors.resize(n);
  uv.reserve(n);
  scale.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    uv.emplace_back(keypoints[k].pt.x, keypoints[k].pt.y);
    scale.push_back(std::pow(m_options.orb.scaleFactor, static_cast<float>(keypoints[k].octave)));
  }
}

RelocalizationFrame WindowRelocalization::describe(const vpImage<unsigned char> &raw)
{
  RelocalizationFrame frame;
  extract(raw, frame.uv, frame.scale, frame.descriptors);
  return frame;
}

DescribedView WindowRelocalization::describeView(const WindowView &view)
{
  DescribedView out;
  out.id = view.id;
  out.cMw = view.cMw;
  if (view.frame) {
    extract(view.frame->raw, out.uv, out.scale, out.descriptors);
  }
  return out;
}

void WindowRelocalization::clear()
{
  m_views.clear();
  m_points = RelocalizationKeyframe();
  m_pointsFrom.clear();
}

RelocalizerOptions WindowRelocalization::matchingOptions()
{
  RelocalizerOptions options;
  options.ratio = 0.9f;
  options.maxDistance = 64;
  options.minimalP3P = true;
  options.ransacIterations = 2000;
  options.refineOnConsensus = true;
  return options;
}

RelocalizationKeyframe WindowRelocalization::windowPoints(const std::vector<WindowView> &views)
{
  RelocalizationKeyframe out;
  if (views.empty()) {
    return out;
  }
  std::vector<std::pair<int, SE3d>> from;
  for (const WindowView &view : views) {
    from.emplace_back(view.id, view.cMw);
  }
  const auto samePose = [](const std::pair<int, SE3d> &x, const std::pair<int, SE3d> &y) {
    return x.first == y.first && x.second.translation() == y.second.translation() &&
           x.second.unitQuaternion().coeffs() == y.second.unitQuaternion().coeffs();
  };
  if (from.size() == m_pointsFrom.size() && std::equal(from.begin(), from.end(), m_pointsFrom.begin(), samePose)) {
    return m_points;
  }
  std::map<int, DescribedView> described;
  for (const WindowView &view : views) {
    // A keyframe's image never changes: its features are kept across queries; its pose is taken anew.
    const auto cached = m_views.find(view.id);
    DescribedView d = cached != m_views.end() ? cached->second : describeView(view);
    d.cMw = view.cMw;
    described[view.id] = std::move(d);
  }
  m_views = described; // keyframes that left the window are forgotten
  out.id = views.back().id;
  for (const auto &entry : described) {
    const DescribedView &a = entry.second;
    // Partners with the widest baseline first: their depths are the best conditioned.
    std::vector<const DescribedView *> partners;
    for (const auto &other : described) {
      if (other.first != entry.first) {
        partners.push_back(&other.second);
      }
    }
    const Eigen::Vector3d centreA = a.cMw.inverse().translation();
    std::sort(partners.begin(), partners.end(), [&centreA](const DescribedView *x, const DescribedView *y) {
      const double dx = (x->cMw.inverse().translation() - centreA).norm();
      const double dy = (y->cMw.inverse().translation() - centreA).norm();
      return dx > dy || (dx == dy && x->id < y->id);
    });
    std::vector<unsigned char> done(a.uv.size(), 0);
    for (const DescribedView *b : partners) {
      triangulateViews(a, *b, m_K, m_options.triangulation, done, out.wX, out.descriptors);
    }
  }
  m_points = out;
  m_pointsFrom = std::move(from);
  return out;
}
} // namespace hslam
