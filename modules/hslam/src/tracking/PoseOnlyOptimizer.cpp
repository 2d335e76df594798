/*
 * H-SLAM for ViSP.
 */
#include "tracking/PoseOnlyOptimizer.h"

#include <Eigen/Cholesky>

namespace hslam
{
bool reprojectionResidual(const SE3d &cTw, const ReprojectionObservation &obs, const PinholeIntrinsics &K,
                          double minDepth, Eigen::Vector2d &residual, Eigen::Matrix<double, 2, 6> *jacobian)
{
  const Eigen::Vector3d cX = cTw * obs.wX;
  if (!(cX.z() >= minDepth)) {
    return false;
  }
  const double iz = 1. / cX.z();
  residual << K.fx * cX.x() * iz + K.cx - obs.uv.x(), K.fy * cX.y() * iz + K.cy - obs.uv.y();
  if (jacobian) {
    Eigen::Matrix<double, 2, 3> dProjection;
    dProjection << K.fx * iz, 0., -K.fx * cX.x() * iz * iz, 0., K.fy * iz, -K.fy * cX.y() * iz * iz;
    *jacobian = dProjection * cTw.jacobianActionLeftPerturbation(obs.wX);
  }
  return true;
}

PoseOnlyResult optimizePoseOnly(const SE3d &cTwInit, const std::vector<ReprojectionObservation> &observations,
                                const PinholeIntrinsics &K, const PoseOnlyOptions &options)
{
  PoseOnlyResult result;
  result.cTw = cTwInit;
  const std::size_t n = observations.size();
  result.inlier.assign(n, true);
  // Three matches fix six unknowns; fewer leave the pose unconstrained (ORB-SLAM2 requires more before calling).
  constexpr std::size_t kMinObservations = 3;
  if (n < kMinObservations) {
    result.inlier.assign(n, false);
    return result;
  }
  const double huberDelta = std::sqrt(options.chi2Threshold);
  Eigen::Vector2d r;
  Eigen::Matrix<double, 2, 6> J;
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robustRounds;
    for (int iteration = 0; iteration < options.iterationsPerRound; ++iteration) {
      Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
      int used = 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (!result.inlier[i] || !reprojectionResidual(result.cTw, observations[i], K, options.minDepth, r, &J)) {
          continue;
        }
        const double information = 1. / observations[i].sigma2;
        double weight = information;
        if (robust) {
          // Huber on the whitened error e = sqrt(chi2): weight delta / e beyond delta (g2o's RobustKernelHuber).
          const double e = std::sqrt(information * r.squaredNorm());
          if (e > huberDelta) {
            weight *= huberDelta / e;
          }
        }
        H.noalias() += weight * J.transpose() * J;
        b.noalias() += weight * J.transpose() * r;
        ++used;
      }
      if (used < static_cast<int>(kMinObservations)) {
        break;
      }
      const Eigen::Matrix<double, 6, 1> delta = H.ldlt().solve(-b);
      if (!delta.allFinite()) {
        break;
      }
      result.cTw = SE3d::exp(delta) * result.cTw;
      if (delta.norm() < options.stepThreshold) {
        break;
      }
    }
    // Re-classify every match, the outliers of earlier rounds included (ORB-SLAM2 lets them come back).
    for (std::size_t i = 0; i < n; ++i) {
      result.inlier[i] = reprojectionResidual(result.cTw, observations[i], K, options.minDepth, r) &&
                         r.squaredNorm() / observations[i].sigma2 <= options.chi2Threshold;
    }
  }
  double sum = 0.;
  result.inliers = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (result.inlier[i] && reprojectionResidual(result.cTw, observations[i], K, options.minDepth, r)) {
      sum += r.squaredNorm();
      ++result.inliers;
    }
  }
  result.inlierRmsePx = result.inliers > 0 ? std::sqrt(sum / result.inliers) : 0.;
  return result;
}
int countReprojectionInliers(const SE3d &cTw, const std::vector<ReprojectionObservation> &observations,
                             const PinholeIntrinsics &K, double chi2, double minDepth)
{
  int inliers = 0;
  for (const ReprojectionObservation &obs : observations) {
    Eigen::Vector2d r;
    if (reprojectionResidual(cTw, obs, K, minDepth, r) && r.squaredNorm() < chi2 * obs.sigma2) {
      ++inliers;
    }
  }
  return inliers;
}
} // namespace hslam
