// Closed-form alignment of two point sets (Umeyama 1991) in SE(3) or Sim(3).
#ifndef HSLAM_EVAL_TRAJECTORY_ALIGNMENT_H
#define HSLAM_EVAL_TRAJECTORY_ALIGNMENT_H

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <vector>

namespace hslam
{
//! Which transformation family aligns an estimate onto the ground truth.
enum class AlignmentMode {
  none, //!< identity
  se3,  //!< rotation + translation
  sim3  //!< rotation + translation + scale (monocular: the scale is unobservable)
};

//! x -> scale * R * x + t.
struct SimilarityTransform {
  double scale = 1.;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d &x) const { return scale * (R * x) + t; }
};

/*!
  Least-squares transform T minimising sum_i ||target_i - T(source_i)||^2 (Umeyama, "Least-squares estimation of
  transformation parameters between two point patterns", PAMI 1991, eq. 40-42: SVD of the cross-covariance with the
  reflection guard S = diag(1, 1, det(U) det(V))).
  \throw vpHSlamException (invalidArgument) if the sizes differ, fewer than 3 points for se3/sim3, or all source
  points coincide for sim3.
*/
VISP_EXPORT SimilarityTransform alignUmeyama(const std::vector<Eigen::Vector3d> &source,
                                             const std::vector<Eigen::Vector3d> &target, AlignmentMode mode);
} // namespace hslam

#endif
