/*
 * H-SLAM for ViSP.
 */
#include "tracking/Relocalizer.h"

#include <algorithm>
#include <opencv2/calib3d.hpp>

#include <Eigen/Geometry>

namespace hslam
{
std::vector<std::pair<int, int>> matchByBow(const RelocalizationKeyframe &keyframe, const RelocalizationFrame &frame,
                                            const RelocalizerOptions &options)
{
  // Best keyframe point per frame keypoint, found node by node (both direct indices are sorted by node id).
  std::vector<int> pointOf(frame.descriptors.size(), -1), distanceOf(frame.descriptors.size(), 257);
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
      int best = 257, second = 257, bestIndex = -1;
      for (std::uint32_t k : fr->features) {
        if (k >= frame.descriptors.size()) {
          continue;
        }
        const int d = hammingDistance(keyframe.descriptors[p], frame.descriptors[k]);
        if (d < best) {
          second = best;
          best = d;
          bestIndex = static_cast<int>(k);
        } else if (d < second) {
          second = d;
        }
      }
      if (bestIndex >= 0 && best <= options.maxDistance &&
          static_cast<float>(best) < options.ratio * static_cast<float>(second) &&
          best < distanceOf[static_cast<std::size_t>(bestIndex)]) {
        pointOf[static_cast<std::size_t>(bestIndex)] = static_cast<int>(p);
        distanceOf[static_cast<std::size_t>(bestIndex)] = best;
      }
    }
    ++kf;
    ++fr;
  }
  std::vector<std::pair<int, int>> matches;
  for (std::size_t k = 0; k < pointOf.size(); ++k) {
    if (pointOf[k] >= 0) {
      matches.emplace_back(pointOf[k], static_cast<int>(k));
    }
  }
  return matches;
}

std::vector<std::pair<int, int>> matchExhaustive(const RelocalizationKeyframe &keyframe,
                                                 const RelocalizationFrame &frame, const RelocalizerOptions &options)
{
  std::vector<int> pointOf(frame.descriptors.size(), -1), distanceOf(frame.descriptors.size(), 257);
  const std::size_t points = std::min(keyframe.descriptors.size(), keyframe.wX.size());
  for (std::size_t p = 0; p < points; ++p) {
    int best = 257, second = 257, bestIndex = -1;
    for (std::size_t k = 0; k < frame.descriptors.size(); ++k) {
      const int d = hammingDistance(keyframe.descriptors[p], frame.descriptors[k]);
      if (d < best) {
        second = best;
        best = d;
        bestIndex = static_cast<int>(k);
      } else if (d < second) {
        second = d;
      }
    }
    if (bestIndex >= 0 && best <= options.maxDistance &&
        static_cast<float>(best) < options.ratio * static_cast<float>(second) &&
        best < distanceOf[static_cast<std::size_t>(bestIndex)]) {
      pointOf[static_cast<std::size_t>(bestIndex)] = static_cast<int>(p);
      distanceOf[static_cast<std::size_t>(bestIndex)] = best;
    }
  }
  std::vector<std::pair<int, int>> matches;
  for (std::size_t k = 0; k < pointOf.size(); ++k) {
    if (pointOf[k] >= 0) {
      matches.emplace_back(pointOf[k], static_cast<int>(k));
    }
  }
  return matches;
}

RelocalizationResult relocalize(const RelocalizationFrame &frame,
                                const std::vector<const RelocalizationKeyframe *> &candidates,
                                const PinholeIntrinsics &K, const RelocalizerOptions &options)
{
  RelocalizationResult result;
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
    for (const auto &m : matches) {
      const Eigen::Vector3d &X = keyframe->wX[static_cast<std::size_t>(m.first)];
      const Eigen::Vector2d &uv = frame.uv[static_cast<std::size_t>(m.second)];
      objectPoints.emplace_back(X.x(), X.y(), X.z());
      imagePoints.emplace_back(uv.x(), uv.y());
      ReprojectionObservation obs;
      obs.wX = X;
      obs.uv = uv;
      observations.push_back(obs);
    }
    cv::Mat rvec, tvec;
    std::vector<int> ransacInliers;
    bool solved = false;
    try {
      solved = cv::solvePnPRansac(objectPoints, imagePoints, cameraMatrix, cv::noArray(), rvec, tvec, false,
                                  options.ransacIterations, static_cast<float>(options.ransacThresholdPx),
                                  options.ransacConfidence, ransacInliers, cv::SOLVEPNP_EPNP);
    } catch (const cv::Exception &) {
      solved = false; // degenerate configuration: try the next candidate
    }
    if (!solved || static_cast<int>(ransacInliers.size()) < options.minMatches) {
      continue;
    }
    cv::Mat R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        rotation(r, c) = R.at<double>(r, c);
      }
    }
    const SE3d cTwPnP(Eigen::Quaterniond(rotation),
                      Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
    const PoseOnlyResult refined = optimizePoseOnly(cTwPnP, observations, K, options.refinement);
    result.inliers = std::max(result.inliers, refined.inliers);
    if (refined.inliers >= options.minInliers) {
      result.success = true;
      result.keyframeId = keyframe->id;
      result.cTw = refined.cTw;
      result.matches = static_cast<int>(matches.size());
      result.inliers = refined.inliers;
      return result;
    }
  }
  return result;
}
} // namespace hslam
