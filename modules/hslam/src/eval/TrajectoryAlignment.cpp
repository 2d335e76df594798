#include "eval/TrajectoryAlignment.h"

#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <string>

namespace hslam
{
namespace
{
//! A rigid transform in 3D needs three non-collinear points.
constexpr size_t kMinAlignmentPoints = 3;
} // namespace

SimilarityTransform alignUmeyama(const std::vector<Eigen::Vector3d> &source, const std::vector<Eigen::Vector3d> &target,
                                 AlignmentMode mode)
{
  if (source.size() != target.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "alignUmeyama: " + std::to_string(source.size()) +
                                                                  " source points for " +
                                                                  std::to_string(target.size()) + " target points");
  }
  SimilarityTransform T;
  if (mode == AlignmentMode::none) {
    return T;
  }
  const size_t n = source.size();
  if (n < kMinAlignmentPoints) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "alignUmeyama: " + std::to_string(n) + " point pairs, at least 3 are needed");
  }
  Eigen::Vector3d muSource = Eigen::Vector3d::Zero();
  Eigen::Vector3d muTarget = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    muSource += source[i];
    muTarget += target[i];
  }
  muSource /= static_cast<double>(n);
  muTarget /= static_cast<double>(n);

  // Umeyama eq. 36 (source variance) and eq. 38 (cross-covariance target x source^T).
  double varianceSource = 0.;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d s = source[i] - muSource;
    const Eigen::Vector3d t = target[i] - muTarget;
    varianceSource += s.squaredNorm();
    covariance += t * s.transpose();
  }
  varianceSource /= static_cast<double>(n);
  covariance /= static_cast<double>(n);

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d S = Eigen::Vector3d::Ones();
  // Eq. 39-40: flip the smallest singular direction when U V^T would be a reflection.
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.) {
    S[2] = -1.;
  }
  T.R = svd.matrixU() * S.asDiagonal() * svd.matrixV().transpose();
  if (mode == AlignmentMode::sim3) {
    if (!(varianceSource > 0.)) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "alignUmeyama: all source points coincide, the scale is undefined");
    }
    // Eq. 42: c = tr(D S) / sigma_source^2.
    T.scale = svd.singularValues().dot(S) / varianceSource;
  }
  // Eq. 41.
  T.t = muTarget - T.scale * T.R * muSource;
  return T;
}
} // namespace hslam
