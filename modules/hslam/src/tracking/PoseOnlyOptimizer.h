/*
 * H-SLAM for ViSP.
 */
/*!
  \file PoseOnlyOptimizer.h
  \brief Indirect step of the hybrid pose estimation (paper section 3.2, step 1): robust pose-only optimisation of
  the reprojection error of 2D-3D matches, with outlier rejection, and the weight K of the geometric term in the
  joint photometric + geometric optimisation (paper eq. 4).

  What it is for: the hybrid tracker first matches the map points seen in the last frame into the new frame by ORB
  descriptor, then estimates the pose from those matches alone; the inliers it keeps feed the joint optimisation,
  whose geometric term they form. This is ORB-SLAM2's Optimizer::PoseOptimization, rewritten on this project's
  SE(3): a few rounds of Gauss-Newton with a Huber kernel; after each round every match is re-classified by its
  chi-square (2 degrees of freedom) against a threshold, outliers leave the next round, and the last rounds drop the
  kernel (the remaining matches are inliers).

  Conventions: poses are cTw (world to camera) updated by left perturbation, cTw <- exp(delta) cTw, twist
  (translation, rotation) as in math/SE3.h; pixel coordinates with (0,0) the centre of the top-left pixel.

  Threading: free functions, no state.
*/
#ifndef HSLAM_TRACKING_POSE_ONLY_OPTIMIZER_H
#define HSLAM_TRACKING_POSE_ONLY_OPTIMIZER_H

#include "features/ImagePyramid.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <cmath>
#include <vector>

namespace hslam
{

//! One 2D-3D match: a map point in world coordinates and the pixel it was matched to.
struct ReprojectionObservation {
  Eigen::Vector3d wX = Eigen::Vector3d::Zero(); //!< world point
  Eigen::Vector2d uv = Eigen::Vector2d::Zero(); //!< matched pixel
  double sigma2 = 1.;                           //!< pixel variance of the match (ORB-SLAM2: scale factor^(2 level))
};

//! Settings (defaults: ORB-SLAM2's PoseOptimization).
struct PoseOnlyOptions {
  int rounds = 4;               //!< optimise / re-classify rounds
  int iterationsPerRound = 10;  //!< Gauss-Newton iterations per round
  int robustRounds = 2;         //!< the first rounds use the Huber kernel, the last ones none
  double chi2Threshold = 5.991; //!< chi-square 95 % quantile, 2 dof: above it a match is an outlier
  double minDepth = 1e-6;       //!< points closer than this (or behind the camera) are outliers, scene units
  double stepThreshold = 1e-10; //!< stop a round when the update's norm is below this
};

//! Outcome of optimizePoseOnly().
struct PoseOnlyResult {
  SE3d cTw;                 //!< optimised pose (the initial one when there were too few matches)
  std::vector<bool> inlier; //!< per observation
  int inliers = 0;          //!< count of true values in inlier
  double inlierRmsePx = 0.; //!< RMS reprojection error of the inliers, pixels
};

/*!
  Reprojection residual (projected - observed, pixels) of one observation and its Jacobian with respect to a left
  perturbation of cTw. Returns false when the point is not in front of the camera (depth < minDepth).
*/
VISP_EXPORT bool reprojectionResidual(const SE3d &cTw, const ReprojectionObservation &obs, const PinholeIntrinsics &K,
                                      double minDepth, Eigen::Vector2d &residual,
                                      Eigen::Matrix<double, 2, 6> *jacobian = nullptr);

//! Observations whose squared reprojection error at \e cTw, over their sigma2, is below \e chi2 (in front of the
//! camera).
VISP_EXPORT int countReprojectionInliers(const SE3d &cTw, const std::vector<ReprojectionObservation> &observations,
                                         const PinholeIntrinsics &K, double chi2, double minDepth = 1e-6);

//! Robust pose-only optimisation from \e cTwInit (see the file comment).
VISP_EXPORT PoseOnlyResult optimizePoseOnly(const SE3d &cTwInit,
                                            const std::vector<ReprojectionObservation> &observations,
                                            const PinholeIntrinsics &K,
                                            const PoseOnlyOptions &options = PoseOnlyOptions());

/*!
  Weight of the geometric term against the photometric one in the joint optimisation (paper eq. 4, the logistic
  utility): K = 5 exp(-2 l) / (1 + exp((30 - N_g) / 4)), N_g the geometric inliers.

  Which level is l = 0: the paper defines l as "the pyramid level at which the optimisation is taking place", and
  also says the geometric residuals weigh most in the early stages of the coarse-to-fine optimisation, shifting to
  the photometric ones later (ARCHITECTURE.md: geometry leads at coarse levels, photometry at fine ones). Both
  counts were built and measured (fast preset, hybrid, median ATE of five runs with the point budget moved by up to
  2 %): counting from the coarsest level used, KITTI 06 0.024 m, Tsukuba 0.25 cm, 7-Scenes 0.053 m, KITTI 06 fed
  every second frame 0.028 m; counting from full resolution, 0.024 m, 0.28 cm, 0.055 m and 0.030 m (one of those
  five runs at 4.8 m). So \e stepFromCoarsest is 0 at the coarsest level and grows towards the finest: the
  matches guide the coarse levels, the sub-pixel photometric alignment decides the final pose (the ORB keypoints
  are integer FAST pixels).
*/
inline double geometricWeight(int stepFromCoarsest, int geometricInliers)
{
  return 5. * std::exp(-2. * stepFromCoarsest) / (1. + std::exp((30. - geometricInliers) / 4.));
}
} // namespace hslam

#endif
