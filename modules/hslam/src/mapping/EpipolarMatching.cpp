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
} // namespace

std::vector<std::pair<int, int>>
matchAlongEpipolarLines(const Eigen::Matrix3d &F, const std::vector<cv::KeyPoint> &first,
                        const cv::Mat &firstDescriptors, const std::vector<cv::KeyPoint> &second,
                        const cv::Mat &secondDescriptors, std::vector<bool> &firstUsed, std::vector<bool> &secondUsed,
                        const EpipolarMatchOptions &options)
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
  struct Candidate {
    int distance, firstIndex, secondIndex;
  };
  std::vector<OrbDescriptor> secondSet(second.size());
  for (size_t i = 0; i < second.size(); ++i) {
    secondSet[i] = descriptorFromBytes(secondDescriptors.ptr<std::uint8_t>(static_cast<int>(i)));
  }
  std::vector<Candidate> candidates;
  Eigen::Vector2d epipole = Eigen::Vector2d::Zero();
  const bool hasEpipole = secondEpipole(F, epipole);
  for (size_t j = 0; j < first.size(); ++j) {
    if (firstUsed[j]) {
      continue;
    }
    const OrbDescriptor a = descriptorFromBytes(firstDescriptors.ptr<std::uint8_t>(static_cast<int>(j)));
    const Eigen::Vector3d line = F * Eigen::Vector3d(first[j].pt.x, first[j].pt.y, 1.);
    const double lineNorm = line.head<2>().norm();
    if (!(lineNorm > 0.)) {
      continue;
    }
    int best = std::numeric_limits<int>::max(), secondBest = best, bestIndex = -1;
    for (size_t i = 0; i < second.size(); ++i) {
      const cv::KeyPoint &k = second[i];
      if (secondUsed[i] || std::abs(k.octave - first[j].octave) > 1) {
        continue;
      }
      const double levelScale = std::pow(options.levelScale, k.octave);
      const Eigen::Vector2d x2(k.pt.x, k.pt.y);
      if (std::abs(line.head<2>().dot(x2) + line.z()) / lineNorm > options.maxLineDistancePx * levelScale) {
        continue;
      }
      if (hasEpipole && (x2 - epipole).norm() < options.minEpipoleDistancePx * levelScale) {
        continue;
      }
      const int d = hammingDistance(a, secondSet[i]);
      if (d < best) {
        secondBest = best;
        best = d;
        bestIndex = static_cast<int>(i);
      } else if (d < secondBest) {
        secondBest = d;
      }
    }
    if (bestIndex >= 0 && best <= options.maxHamming && best < options.ratio * secondBest) {
      candidates.push_back({best, static_cast<int>(j), bestIndex});
    }
  }
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
