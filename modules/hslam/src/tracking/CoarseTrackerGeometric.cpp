/*
 * H-SLAM for ViSP.
 */
// The geometric term of the joint photometric + geometric pose optimisation (paper eq. 1-4). See CoarseTracker.h,
// GeometricTerm.
#include "tracking/CoarseTracker.h"

#include "tracking/PoseOnlyOptimizer.h"

#include <cmath>

namespace hslam
{
namespace
{
//! Huber threshold on the squared reprojection error, pixels^2: the 95 % chi-square quantile with 2 dof.
constexpr double kGeometricHuber2 = 5.991;
//! Points closer than this (reference scene units) to the new camera give no residual.
constexpr double kMinDepth = 1e-6;
} // namespace

double CoarseTracker::geometricEnergy(const GeometricTerm &term, const PinholeIntrinsics &K0, const SE3d &newMref,
                                      Eigen::Matrix<double, 8, 8> *H, Eigen::Matrix<double, 8, 1> *b)
{
  const double delta = std::sqrt(kGeometricHuber2);
  double energy = 0.;
  Eigen::Vector2d r;
  Eigen::Matrix<double, 2, 6> J;
  const size_t n = std::min(term.Xref.size(), term.uv.size());
  const bool weighted = term.weights.size() == n;
  for (size_t i = 0; i < n; ++i) {
    const double w = weighted ? term.weights[i] : 1.;
    ReprojectionObservation obs;
    obs.wX = term.Xref[i];
    obs.uv = term.uv[i];
    if (!reprojectionResidual(newMref, obs, K0, kMinDepth, r, H ? &J : nullptr)) {
      energy += w * kGeometricHuber2; // behind the camera: a saturated residual, no gradient
      continue;
    }
    const double e2 = r.squaredNorm();
    double weight = w;
    if (e2 <= kGeometricHuber2) {
      energy += w * e2;
    } else {
      const double e = std::sqrt(e2);
      energy += w * (2. * delta * e - kGeometricHuber2);
      weight = w * delta / e;
    }
    if (H) {
      H->topLeftCorner<6, 6>().noalias() += weight * J.transpose() * J;
      b->head<6>().noalias() += weight * J.transpose() * r;
    }
  }
  return energy;
}
} // namespace hslam
