/*
 * H-SLAM for ViSP.
 */
/*!
  \file EpipolarMatching.h
  \brief ORB matching between two views guided by their epipolar geometry: each keypoint of the first view is
  compared only with the second view's keypoints near its epipolar line.

  What it is for: the two-view initializer matches by brute force over all keypoint pairs, with Lowe's ratio test
  against every other keypoint of the image. Under large motion (KITTI every 4th frame: 4 m forward) and repeated
  texture (foliage, road) that ratio test rejects most right matches, because somewhere in the image there is a
  similar descriptor; the initializer then sees 30-60 matches and gives up. Once an essential matrix is known from
  those few, the competitors of a keypoint are only the few keypoints near its epipolar line, and the ratio test
  among them keeps many more right matches (ORB-SLAM2's SearchForTriangulation does the same between keyframes).

  Method: line l2 = F x1 in the second image; candidates within maxLineDistancePx * levelScale^octave of it, at most
  one octave apart, and not within minEpipoleDistancePx * levelScale^octave of the epipole (every line passes
  there, so it discriminates nothing); best Hamming distance at most maxHamming and below ratio times the second
  best; each second-view keypoint kept for its closest first-view keypoint only.

  Stateless and thread-safe.
*/
#ifndef HSLAM_MAPPING_EPIPOLAR_MATCHING_H
#define HSLAM_MAPPING_EPIPOLAR_MATCHING_H

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <utility>
#include <vector>

namespace hslam
{
//! Thresholds of matchAlongEpipolarLines (ORB-SLAM2's SearchForTriangulation values where it has one).
struct EpipolarMatchOptions {
  double maxLineDistancePx = 2.;     //!< distance to the epipolar line at octave 0, pixels (grows by levelScale)
  double minEpipoleDistancePx = 10.; //!< keypoints this close to the epipole are not matched (ORB-SLAM2: 10)
  double levelScale = 1.2;           //!< scale between ORB octaves
  int maxHamming = 50;               //!< Hamming distance accepted at most (ORB-SLAM2 TH_LOW)
  double ratio = 0.8;                //!< best distance below this times the second best among the candidates
};

/*!
  Matches between the first view's keypoints \e first (descriptors \e firstDescriptors, 32-byte ORB rows) and the
  second view's \e second, under the fundamental matrix \e F (pixels, x2^T F x1 = 0). Keypoints flagged in
  \e firstUsed / \e secondUsed (sized as the keypoints) take no part; those matched here are flagged too.
  \return pairs (first index, second index).
*/
VISP_EXPORT std::vector<std::pair<int, int>>
matchAlongEpipolarLines(const Eigen::Matrix3d &F, const std::vector<cv::KeyPoint> &first,
                        const cv::Mat &firstDescriptors, const std::vector<cv::KeyPoint> &second,
                        const cv::Mat &secondDescriptors, std::vector<bool> &firstUsed, std::vector<bool> &secondUsed,
                        const EpipolarMatchOptions &options = EpipolarMatchOptions());
} // namespace hslam

#endif
