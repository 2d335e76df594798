/*
 * H-SLAM for ViSP.
 */
#include "tracking/Relocalizer.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>

#include <Eigen/Geometry>

namespace hslam
{
namespace
{
//! Larger than any Hamming distance of 256-bit descriptors.
constexpr int kNoDistance = 257;

//! Best and second-best distance of one keyframe point over the keypoints offered, and the best one's index.
struct BestTwo {
  int best = kNoDistance, second = kNoDistance, index = -1;
  void offer(int distance, int keypoint)
  {
    if (distance < best) {
      second = best;
      best = distance;
      index = keypoint;
    } else if (distance < second) {
      second = distance;
    }
  }
};

//! Each frame keypoint keeps the keyframe point that matched it best (one point per keypoint).
class KeypointAssignment
{
public:
  explicit KeypointAssignment(std::size_t keypoints) : m_pointOf(keypoints, -1), m_distanceOf(keypoints, kNoDistance) {}
  //! Point \e point's best keypoint, if it passes the distance and ratio tests and beats the keypoint's current one.
  void propose(int point, const BestTwo &b, const RelocalizerOptions &options)
  {
    if (b.index < 0 || b.best > options.maxDistance ||
        !(static_cast<float>(b.best) < options.ratio * static_cast<float>(b.second))) {
      return;
    }
    const std::size_t k = static_cast<std::size_t>(b.index);
    if (b.best < m_distanceOf[k]) {
      m_pointOf[k] = point;
      m_distanceOf[k] = b.best;
    }
  }
  //! Pairs (keyframe point, frame keypoint), in keypoint order.
  std::vector<std::pair<int, int>> matches() const
  {
    std::vector<std::pair<int, int>> out;
    for (std::size_t k = 0; k < m_pointOf.size(); ++k) {
      if (m_pointOf[k] >= 0) {
        out.emplace_back(m_pointOf[k], static_cast<int>(k));
      }
    }
    return out;
  }

private:
  std::vector<int> m_pointOf, m_distanceOf;
};
} // namespace

std::vector<std::pair<int, int>> matchByBow(const RelocalizationKeyframe &keyframe, const RelocalizationFrame &frame,
                                            const RelocalizerOptions &options)
{
  // Best keyframe point per frame keypoint, found node by node (both direct indices are sorted by node id).
  KeypointAssignment assignment(frame.descriptors.size());
  auto kf = keyframe.direct.begin();
  auto fr = frame.direct.begin();
  while (kf != keyframe.direct.end() && fr != frame.direct.end()) {
    if (kf->nodeId < fr->nodeId) {
      ++kf;
      continue;
    }
    if (fr->nodeId < kf->nodeId) {
      ++fr;
      continue;
    }
    for (std::uint32_t p : kf->features) {
      if (p >= keyframe.descriptors.size() || p >= keyframe.wX.size()) {
        continue;
      }
      BestTwo b;
      for (std::uint32_t k : fr->features) {
        if (k < frame.descriptors.size()) {
          b.offer(hammingDistance(keyframe.descriptors[p], frame.descriptors[k]), static_cast<int>(k));
        }
      }
      assignment.propose(static_cast<int>(p), b, options);
    }
    ++kf;
    ++fr;
  }
  return assignment.matches();
}

std::vector<std::pair<int, int>> matchExhaustive(const RelocalizationKeyframe &keyframe,
                                                 const RelocalizationFrame &frame, const RelocalizerOptions &options)
{
  KeypointAssignment assignment(frame.descriptors.size());
  const std::size_t points = std::min(keyframe.descriptors.size(), keyframe.wX.size());
  for (std::size_t p = 0; p < points; ++p) {
    BestTwo b;
    for (std::size_t k = 0; k < frame.descriptors.size(); ++k) {
      b.offer(hammingDistance(keyframe.descriptors[p], frame.descriptors[k]), static_cast<int>(k));
    }
    assignment.propose(static_cast<int>(p), b, options);
  }
  return assignment.matches();
}

namespace
{
//! The 3-D / 2-D pairs of \e matches (keyframe point, frame keypoint) for OpenCV and as observations (with the
//! keypoint's scale as its variance when known).
void matchedPairs(const RelocalizationKeyframe &keyframe, const RelocalizationFrame &frame,
                  const std::vector<std::pair<int, int>> &matches, std::vector<cv::Point3d> &objectPoints,
                  std::vector<cv::Point2d> &imagePoints, std::vector<ReprojectionObservation> &observations)
{
  for (const auto &m : matches) {
    const Eigen::Vector3d &X = keyframe.wX[static_cast<std::size_t>(m.first)];
    const Eigen::Vector2d &uv = frame.uv[static_cast<std::size_t>(m.second)];
    objectPoints.emplace_back(X.x(), X.y(), X.z());
    imagePoints.emplace_back(uv.x(), uv.y());
    ReprojectionObservation obs;
    obs.wX = X;
    obs.uv = uv;
    if (static_cast<std::size_t>(m.second) < frame.scale.size()) {
      const double s = static_cast<double>(frame.scale[static_cast<std::size_t>(m.second)]);
      obs.sigma2 = s * s;
    }
    observations.push_back(obs);
  }
}

//! PnP RANSAC (EPnP or AP3P): false on a degenerate configuration or fewer than minMatches inliers.
bool pnpRansacPose(const std::vector<cv::Point3d> &objectPoints, const std::vector<cv::Point2d> &imagePoints,
                   const cv::Mat &cameraMatrix, const RelocalizerOptions &options, SE3d &cTw,
                   std::vector<int> &ransacInliers)
{
  cv::Mat rvec, tvec;
  bool solved = false;
  try {
    solved = cv::solvePnPRansac(objectPoints, imagePoints, cameraMatrix, cv::noArray(), rvec, tvec, false,
                                options.ransacIterations, static_cast<float>(options.ransacThresholdPx),
                                options.ransacConfidence, ransacInliers,
                                options.minimalP3P ? cv::SOLVEPNP_AP3P : cv::SOLVEPNP_EPNP);
  } catch (const cv::Exception &) {
    solved = false; // degenerate configuration: try the next candidate
  }
  if (!solved || static_cast<int>(ransacInliers.size()) < options.minMatches) {
    return false;
  }
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d rotation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      rotation(r, c) = R.at<double>(r, c);
    }
  }
  cTw = SE3d(Eigen::Quaterniond(rotation), Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
  return true;
}

/*!
  With refineOnConsensus, the PnP pose is refined on the RANSAC inliers first (ORB-SLAM2 too): with loose matching
  most matches are wrong, and a robust optimisation over all of them is pulled away from the PnP pose (measured on
  7-Scenes after a 40-frame cover: 20-41 RANSAC inliers of about 210 matches, 0 left after refining on all). From
  that pose every match is classified again: the observations that agree with it, and the pose, are returned.
  Without it, every observation and the PnP pose.
*/
std::vector<ReprojectionObservation> observationsToRefine(const SE3d &cTwPnP,
                                                          const std::vector<ReprojectionObservation> &observations,
                                                          const std::vector<int> &ransacInliers,
                                                          const PinholeIntrinsics &K, const RelocalizerOptions &options,
                                                          SE3d &cTwStart)
{
  cTwStart = cTwPnP;
  if (!options.refineOnConsensus) {
    return observations;
  }
  std::vector<ReprojectionObservation> consensus;
  consensus.reserve(ransacInliers.size());
  for (int i : ransacInliers) {
    if (i >= 0 && static_cast<std::size_t>(i) < observations.size()) {
      consensus.push_back(observations[static_cast<std::size_t>(i)]);
    }
  }
  cTwStart = optimizePoseOnly(cTwPnP, consensus, K, options.refinement).cTw;
  std::vector<ReprojectionObservation> refinedOn;
  for (const ReprojectionObservation &obs : observations) {
    Eigen::Vector2d r;
    if (reprojectionResidual(cTwStart, obs, K, options.refinement.minDepth, r) &&
        r.squaredNorm() <= options.refinement.chi2Threshold * obs.sigma2) {
      refinedOn.push_back(obs);
    }
  }
  return refinedOn;
}
} // namespace

RelocalizationResult relocalize(const RelocalizationFrame &frame,
                                const std::vector<const RelocalizationKeyframe *> &candidates,
                                const PinholeIntrinsics &K, const RelocalizerOptions &options)
{
  RelocalizationResult result;
  RelocalizationResult nearMiss; // only its near-miss fields: reported on failure
  const cv::Mat cameraMatrix = (cv::Mat_<double>(3, 3) << K.fx, 0., K.cx, 0., K.fy, K.cy, 0., 0., 1.);
  for (const RelocalizationKeyframe *keyframe : candidates) {
    if (!keyframe) {
      continue;
    }
    ++result.candidatesTried;
    const std::vector<std::pair<int, int>> matches =
        options.exhaustive ? matchExhaustive(*keyframe, frame, options) : matchByBow(*keyframe, frame, options);
    result.matches = std::max(result.matches, static_cast<int>(matches.size())); // best so far, for logs
    if (static_cast<int>(matches.size()) < options.minMatches) {
      continue;
    }
    std::vector<cv::Point3d> objectPoints;
    std::vector<cv::Point2d> imagePoints;
    std::vector<ReprojectionObservation> observations;
    matchedPairs(*keyframe, frame, matches, objectPoints, imagePoints, observations);
    SE3d cTwPnP;
    std::vector<int> ransacInliers;
    if (!pnpRansacPose(objectPoints, imagePoints, cameraMatrix, options, cTwPnP, ransacInliers)) {
      continue;
    }
    SE3d cTwStart;
    const std::vector<ReprojectionObservation> refinedOn =
        observationsToRefine(cTwPnP, observations, ransacInliers, K, options, cTwStart);
    const PoseOnlyResult refined = optimizePoseOnly(cTwStart, refinedOn, K, options.refinement);
    result.inliers = std::max(result.inliers, refined.inliers);
    if (refined.inliers >= options.minInliers) {
      result.success = true;
      result.keyframeId = keyframe->id;
      result.cTw = refined.cTw;
      result.matches = static_cast<int>(matches.size());
      result.inliers = refined.inliers;
      for (std::size_t i = 0; i < refinedOn.size() && i < refined.inlier.size(); ++i) {
        if (refined.inlier[i]) {
          result.inlierObservations.push_back(refinedOn[i]);
        }
      }
      return result;
    }
    if (refined.inliers >= options.minMatches && refined.inliers > nearMiss.nearMissInliers &&
        refined.cTw.translation().allFinite()) {
      nearMiss.nearMissKeyframeId = keyframe->id;
      nearMiss.nearMissCTw = refined.cTw;
      nearMiss.nearMissInliers = refined.inliers;
    }
  }
  result.nearMissKeyframeId = nearMiss.nearMissKeyframeId; // failed: the best pose that fell short, if any
  result.nearMissCTw = nearMiss.nearMissCTw;
  result.nearMissInliers = nearMiss.nearMissInliers;
  return result;
}

double medianDepth(const SE3d &cTw, const std::vector<Eigen::Vector3d> &wX)
{
  std::vector<double> depths;
  depths.reserve(wX.size());
  for (const Eigen::Vector3d &X : wX) {
    depths.push_back((cTw * X).z());
  }
  if (depths.empty()) {
    return 0.;
  }
  const auto middle = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
  std::nth_element(depths.begin(), middle, depths.end());
  return *middle;
}

double medianInlierDepth(const RelocalizationResult &r)
{
  std::vector<Eigen::Vector3d> wX;
  wX.reserve(r.inlierObservations.size());
  for (const ReprojectionObservation &o : r.inlierObservations) {
    wX.push_back(o.wX);
  }
  return medianDepth(r.cTw, wX);
}

FixAgreement compareFixes(const SE3d &previousCMw, const SE3d &currentCMw, double medianDepth)
{
  FixAgreement a;
  const SE3d relative = currentCMw * previousCMw.inverse();
  a.angleDeg = Eigen::AngleAxisd(relative.rotationMatrix()).angle() * 180. / M_PI;
  const double moved = (currentCMw.inverse().translation() - previousCMw.inverse().translation()).norm();
  if (!(medianDepth > 0.)) {
    return a;
  }
  a.depthShare = moved / medianDepth;
  a.agrees = a.angleDeg <= kFixAgreementMaxRotationDeg && a.depthShare <= kFixAgreementMaxDepthShare;
  return a;
}
} // namespace hslam
