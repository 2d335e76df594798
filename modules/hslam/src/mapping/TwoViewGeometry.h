/*
 * H-SLAM for ViSP.
 */
/*!
  \file TwoViewGeometry.h
  \brief Two-view geometry helpers of the initializer: ORB-SLAM2 model scores, linear triangulation, the
  cheirality / reprojection / parallax check of a motion hypothesis, and a Sampson-error refinement of (R, t).

  Conventions: p1 are pixels in the first image, p2 their matches in the second; a motion (R, t) maps first-camera
  points to the second camera, X2 = R X1 + t. All functions are stateless and thread-safe.
*/
#ifndef HSLAM_MAPPING_TWO_VIEW_GEOMETRY_H
#define HSLAM_MAPPING_TWO_VIEW_GEOMETRY_H

#include "features/ImagePyramid.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>
#include <Eigen/StdVector>

#include <vector>

namespace hslam
{
using PixelVector = std::vector<Eigen::Vector2d, Eigen::aligned_allocator<Eigen::Vector2d>>;

/*!
  ORB-SLAM2's homography score (Initializer::CheckHomography): symmetric transfer errors e / sigma^2, each
  truncated at the chi-square 95 % bound for 2 DOF (5.991); a match adds (5.991 - e / sigma^2) per direction when
  both are within the bound, and is then flagged as an inlier. \e H21 maps first-image pixels to the second.
*/
VISP_EXPORT double homographyScore(const Eigen::Matrix3d &H21, const PixelVector &p1, const PixelVector &p2,
                                   double sigma, std::vector<unsigned char> &inliers);

/*!
  ORB-SLAM2's fundamental score (Initializer::CheckFundamental): squared point-to-epipolar-line distances in both
  images, rejected above the chi-square 95 % bound for 1 DOF (3.841) and scored against the 2-DOF bound (5.991) so
  that both models are scored on the same scale. \e F21 satisfies p2^T F21 p1 = 0.
*/
VISP_EXPORT double fundamentalScore(const Eigen::Matrix3d &F21, const PixelVector &p1, const PixelVector &p2,
                                    double sigma, std::vector<unsigned char> &inliers);

/*!
  Linear (DLT) triangulation in normalised coordinates (x = K^-1 p) with cameras [I|0] and [R|t] (Hartley &
  Zisserman, sec. 12.2). Returns false when the point is at infinity or not finite.
*/
VISP_EXPORT bool triangulateLinear(const Eigen::Vector2d &x1, const Eigen::Vector2d &x2, const Eigen::Matrix3d &R,
                                   const Eigen::Vector3d &t, Eigen::Vector3d &X1);

//! Result of checking one motion hypothesis against the matches.
struct MotionCheck {
  int numGood = 0;                 //!< matches passing cheirality and reprojection (any parallax)
  std::vector<unsigned char> good; //!< per match: passed
  std::vector<Eigen::Vector3d> X1; //!< per match: point in the first camera (valid where good)
  std::vector<double> parallaxDeg; //!< per match: triangulation angle, degrees
  double medianParallaxDeg = 0.;   //!< over the good matches
};

/*!
  ORB-SLAM2's CheckRT: triangulate every match flagged in \e candidates, keep it when it lies in front of both
  cameras (points with a tiny parallax, whose sign of depth is meaningless, are not tested for cheirality) and
  its squared reprojection error in both images is below \e maxReprojErrSq (pixels^2).
*/
VISP_EXPORT MotionCheck checkMotion(const Eigen::Matrix3d &R, const Eigen::Vector3d &t, const PinholeIntrinsics &K,
                                    const PixelVector &p1, const PixelVector &p2,
                                    const std::vector<unsigned char> &candidates, double maxReprojErrSq);

/*!
  Refine (R, t) (|t| = 1 kept) by Levenberg-Marquardt on the Sampson epipolar errors of the matches flagged in
  \e inliers (Hartley & Zisserman eq. 11.9), with a Huber kernel whose width follows the residuals' robust spread
  (1.345 sigma, capped at \e huberPx pixels). The 5-point RANSAC
  solution is fitted to 5 points only; this uses all inliers. Returns false (and leaves R, t) if it does not
  improve the cost. When \e translationDirSigmaDeg is given, it receives the standard deviation (degrees) of the
  translation direction along its worst axis, from the Gauss-Newton covariance sigma_r^2 (J^T W J)^-1 with the
  rotation marginalised out (Schur complement) and sigma_r the robust (MAD) spread of the residuals: a short
  baseline lets rotation absorb translation, which shows here as a large value.
*/
VISP_EXPORT bool refineRelativePose(Eigen::Matrix3d &R, Eigen::Vector3d &t, const PinholeIntrinsics &K,
                                    const PixelVector &p1, const PixelVector &p2,
                                    const std::vector<unsigned char> &inliers, double huberPx,
                                    double *translationDirSigmaDeg = nullptr);
} // namespace hslam

#endif
