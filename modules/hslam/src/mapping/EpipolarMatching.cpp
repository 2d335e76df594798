/*
 * H-SLAM for ViSP.
 */
#include "mapping/EpipolarMatching.h"

#include "features/BinaryDescriptor.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace hslam
{
namespace
{
//! The epipole of the second view (e2^T F = 0: orthogonal to F's columns), or none when it is at infinity.
bool secondEpipole(const Eigen::Matrix3d &F, Eigen::Vector2d &e)
{
  Eigen::Vector3d best = F.col(0).cross(F.col(1));
  for (const Eigen::Vector3d &c :
       {Eigen::Vector3d(F.col(0).cross(F.col(2))), Eigen::Vector3d(F.col(1).cross(F.col(2)))}) {
    if (c.norm() > best.norm()) {
      best = c;
    }
  }
  if (!(std::abs(best.z()) > 1e-9 * best.norm())) {
    return false;
  }
  e = best.head<2>() / best.z();
  return true;
}

//! A first-view keypoint's best match on its epipolar line, with its Hamming distance.
struct Candidate {
  int distance, firstIndex, secondIndex;
};

//! What is fixed for one call: the second view's keypoints, descriptors and flags, the epipole and the options.
struct SecondView {
  const std::vector<cv::KeyPoint> &keypoints;
  std::vector<OrbDescriptor> descriptors;
  const std::vector<bool> &used;
  bool hasEpipole;
  Eigen::Vector2d epipole;
  const EpipolarMatchOptions &options;
};

/*!
  The closest free second-view keypoint to \e keypoint (descriptor \e d) within its epipolar band, when it passes
  the distance and ratio tests.
*/
bool closestOnLine(const Eigen::Matrix3d &F, const cv::KeyPoint &keypoint, const OrbDescriptor &d, const SecondView &v,
                   int &index, int &distance)
{
  const Eigen::Vector3d line = F * Eigen::Vector3d(keypoint.pt.x, keypoint.pt.y, 1.);
  const double lineNorm = line.head<2>().norm();
  if (!(lineNorm > 0.)) {
    return false;
  }
  int best = std::numeric_limits<int>::max(), secondBest = best, bestIndex = -1;
  for (size_t i = 0; i < v.keypoints.size(); ++i) {
    const cv::KeyPoint &k = v.keypoints[i];
    if (v.used[i] || std::abs(k.octave - keypoint.octave) > 1) {
      continue;
    }
    const double levelScale = std::pow(v.options.levelScale, k.octave);
    const Eigen::Vector2d x2(k.pt.x, k.pt.y);
    if (std::abs(line.head<2>().dot(x2) + line.z()) / lineNorm > v.options.maxLineDistancePx * levelScale) {
      continue;
    }
    if (v.hasEpipole && (x2 - v.epipole).norm() < v.options.minEpipoleDistancePx * levelScale) {
      continue;
    }
    const int dist = hammingDistance(d, v.descriptors[i]);
    if (dist < best) {
      secondBest = best;
      best = dist;
      bestIndex = static_cast<int>(i);
    } else if (dist < secondBest) {
      secondBest = dist;
    }
  }
  if (bestIndex < 0 || best > v.options.maxHamming || !(best < v.options.ratio * secondBest)) {
    return false;
  }
  index = bestIndex;
  distance = best;
  return true;
}

void checkInputs(const std::vector<cv::KeyPoint> &first, const cv::Mat &firstDescriptors,
                 const std::vector<cv::KeyPoint> &second, const cv::Mat &secondDescriptors,
                 const std::vector<bool> &firstUsed, const std::vector<bool> &secondUsed)
{
  for (const cv::Mat *d : {&firstDescriptors, &secondDescriptors}) {
    if (d->type() != CV_8U || (d->rows > 0 && d->cols != kOrbDescriptorBytes)) {
      throw vpHSlamException(vpHSlamException::invalidArgument, "matchAlongEpipolarLines: ORB descriptors are rows "
                                                                "of 32 bytes");
    }
  }
  if (static_cast<size_t>(firstDescriptors.rows) != first.size() ||
      static_cast<size_t>(secondDescriptors.rows) != second.size() || firstUsed.size() != first.size() ||
      secondUsed.size() != second.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "matchAlongEpipolarLines: keypoints, descriptors and flags differ in number");
  }
}
} // namespace

std::vector<std::pair<int, int>>
matchAlongEpipolarLines(const Eigen::Matrix3d &F, const std::vector<cv::KeyPoint> &first,
                        const cv::Mat &firstDescriptors, const std::vector<cv::KeyPoint> &second,
                        const cv::Mat &secondDescriptors, std::vector<bool> &firstUsed, std::vector<bool> &secondUsed,
                        const EpipolarMatchOptions &options)
{
  checkInputs(first, firstDescriptors, second, secondDescriptors, firstUsed, secondUsed);
  SecondView view{second, std::vector<OrbDescriptor>(second.size()), secondUsed, false, Eigen::Vector2d::Zero(),
                  options};
  for (size_t i = 0; i < second.size(); ++i) {
    view.descriptors[i] = descriptorFromBytes(secondDescriptors.ptr<std::uint8_t>(static_cast<int>(i)));
  }
  view.hasEpipole = secondEpipole(F, view.epipole);
  std::vector<Candidate> candidates;
  for (size_t j = 0; j < first.size(); ++j) {
    int index = -1, distance = 0;
    if (!firstUsed[j] &&
        closestOnLine(F, first[j], descriptorFromBytes(firstDescriptors.ptr<std::uint8_t>(static_cast<int>(j))), view,
                      index, distance)) {
      candidates.push_back({distance, static_cast<int>(j), index});
    }
  }
  // Each second-view keypoint for its closest first-view keypoint (ties: the first in order).
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate &a, const Candidate &b) { return a.distance < b.distance; });
  std::vector<std::pair<int, int>> matches;
  for (const Candidate &c : candidates) {
    if (!secondUsed[static_cast<size_t>(c.secondIndex)]) {
      secondUsed[static_cast<size_t>(c.secondIndex)] = firstUsed[static_cast<size_t>(c.firstIndex)] = true;
      matches.emplace_back(c.firstIndex, c.secondIndex);
    }
  }
  return matches;
}
} // namespace hslam
