/*
 * H-SLAM for ViSP.
 */
/*!
  \file Sim3Solver.h
  \brief Loop verification: the similarity between two keyframes from 3D-3D point matches (paper sec. 3.4).

  What it is for: a loop candidate and the current keyframe each see matched map points in their own camera frame
  (X1 in camera 1, X2 in camera 2, with the pixels that observed them). hornSim3() is B. K. P. Horn's closed form
  ("Closed-form solution of absolute orientation using unit quaternions", JOSA A 4(4), 1987): the rotation is the
  eigenvector of the largest eigenvalue of Horn's 4x4 matrix N built from the centred cross-covariance, the scale
  the ratio sum(X2' . R X1') / sum |X1'|^2 (Horn's asymmetric form, as ORB-SLAM), the translation from the
  centroids. estimateSim3Ransac() draws 3 matches at a time (ORB-SLAM's Sim3Solver), keeps the hypothesis with the
  most matches whose reprojection error is below maxReprojectionPx in BOTH images (X1 mapped into camera 2 and X2
  into camera 1), re-estimates it from all its inliers, and refines it by non-linear least squares on the two-way
  reprojection errors (Ceres, Huber loss); it fails below minInliers.

  Threading: pure functions; the RANSAC sampler is seeded from the options (deterministic).
*/
#ifndef HSLAM_LOOP_SIM3_SOLVER_H
#define HSLAM_LOOP_SIM3_SOLVER_H

#include "features/ImagePyramid.h"
#include "math/Sim3.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <vector>

namespace hslam
{

//! One 3D-3D match: the same map point seen by keyframe 1 and keyframe 2.
struct Sim3Correspondence {
  Eigen::Vector3d X1;  //!< in camera 1
  Eigen::Vector3d X2;  //!< in camera 2
  Eigen::Vector2d uv1; //!< pixel where camera 1 observed it
  Eigen::Vector2d uv2; //!< pixel where camera 2 observed it
};

//! Settings (defaults: ORB-SLAM2's loop closing, SetRansacParameters(0.99, 20, 300) and chi2(0.01, 2 dof) = 9.21).
struct Sim3RansacOptions {
  int maxIterations = 300;          //!< hypotheses drawn at most
  double confidence = 0.99;         //!< stop early once a hypothesis this likely has no outlier in its sample
  int minInliers = 20;              //!< matches a result needs (both ways within the threshold)
  double maxReprojectionPx = 3.035; //!< sqrt(9.21): reprojection error accepted in each image, pixels
  unsigned int seed = 1;            //!< of the sampler
  bool refine = true;               //!< non-linear refinement on the inliers
};

//! What estimateSim3Ransac() found.
struct Sim3Estimate {
  bool success = false;
  Sim3d S21;                 //!< X2 = S21 * X1
  std::vector<bool> inliers; //!< per correspondence
  int inlierCount = 0;
  int iterations = 0;            //!< hypotheses drawn
  double rmsReprojectionPx = 0.; //!< over the inliers, both images
};

/*!
  Horn's closed form (see file comment): S21 minimising sum |X2_i - S21 X1_i|^2 in rotation and translation, with
  Horn's scale. \exception vpHSlamException::invalidArgument for fewer than 3 pairs, sizes that differ, or all X1
  coincident.
*/
VISP_EXPORT Sim3d hornSim3(const std::vector<Eigen::Vector3d> &X1, const std::vector<Eigen::Vector3d> &X2);

//! RANSAC + refinement (see file comment); K1, K2 the pinhole intrinsics of the two keyframes.
VISP_EXPORT Sim3Estimate estimateSim3Ransac(const std::vector<Sim3Correspondence> &matches, const PinholeIntrinsics &K1,
                                            const PinholeIntrinsics &K2,
                                            const Sim3RansacOptions &options = Sim3RansacOptions());

/*!
  Refine S21 on the given matches by minimising the two-way reprojection errors (Ceres, Huber loss at
  \e huberPx). Returns false when the solver failed (S21 unchanged).
*/
VISP_EXPORT bool refineSim3(const std::vector<Sim3Correspondence> &matches, const PinholeIntrinsics &K1,
                            const PinholeIntrinsics &K2, double huberPx, Sim3d &S21);
} // namespace hslam

#endif
