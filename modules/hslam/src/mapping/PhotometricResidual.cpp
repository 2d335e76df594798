/*
 * H-SLAM for ViSP.
 */
#include "mapping/PhotometricResidual.h"

#include "common/RobustWeights.h"
#include "map/AffineBrightness.h"

#include <cmath>

namespace hslam
{
void FramePairPrecalc::set(const SE3d &hostMw, double aHost, double bHostIn, double exposureHost, const SE3d &targetMw,
                           double aTarget, double bTarget, double exposureTarget)
{
  const SE3d T_th = targetMw * hostMw.inverse();
  R_th = T_th.rotationMatrix();
  t_th = T_th.translation();
  AffineBrightness host, target;
  host.a = aHost;
  host.b = bHostIn;
  target.a = aTarget;
  target.b = bTarget;
  AffineBrightness::transfer(exposureHost, host, exposureTarget, target, a_th, b_th);
  bHost = bHostIn;

  // Target: T_th <- exp(d_t) T_th, so eps = d_t; alpha = a_t - a_h; beta = b_t - a_th b_h (linearised).
  dRelative_dTarget.setZero();
  dRelative_dTarget.topLeftCorner<6, 6>().setIdentity();
  dRelative_dTarget(6, 6) = 1.;
  dRelative_dTarget(7, 6) = -a_th * bHost;
  dRelative_dTarget(7, 7) = 1.;
  // Host: T_th <- T_th exp(-d_h) = exp(-Ad(T_th) d_h) T_th (DSO's adjoint chain rule).
  dRelative_dHost.setZero();
  dRelative_dHost.topLeftCorner<6, 6>() = -T_th.adjoint();
  dRelative_dHost(6, 6) = -1.;
  dRelative_dHost(7, 6) = a_th * bHost;
  dRelative_dHost(7, 7) = -a_th;
}

ResidualState evaluatePattern(const PhotometricSettings &settings, const PyramidLevel &target,
                              const FramePairPrecalc &pair, const PointObservation &point, double &energy,
                              PatternLinearization *lin)
{
  energy = settings.outlierEnergy;
  const double rho = point.idepth;
  if (!(rho > 0.)) {
    return ResidualState::outOfBounds;
  }
  const PinholeIntrinsics &K = settings.K;
  const double fxInv = 1. / K.fx;
  const double fyInv = 1. / K.fy;
  const Eigen::Vector3d &t = pair.t_th;
  // Two passes with the same arithmetic as one: first every pattern pixel is projected and its four interpolation
  // pixels are prefetched, then they are read. The target images of a window (3.7 MB each at 640x480) do not stay
  // in cache, and reading each pixel right after projecting it left the core waiting on one cache miss at a time
  // (a quarter of a whole run on one load).
  std::array<float, kPatternSize> up, vp;
  std::array<double, kPatternSize> xn, yn, iz;
  for (int k = 0; k < kPatternSize; ++k) {
    const double uk = point.u + kPattern[k][0];
    const double vk = point.v + kPattern[k][1];
    const Eigen::Vector3d m((uk - K.cx) * fxInv, (vk - K.cy) * fyInv, 1.);
    // q = rho * (point in target camera): finite even for points at infinity (rho -> 0).
    const Eigen::Vector3d q = pair.R_th * m + rho * t;
    if (!(q.z() > 0.)) {
      return ResidualState::outOfBounds;
    }
    const size_t i = static_cast<size_t>(k);
    iz[i] = 1. / q.z();
    xn[i] = q.x() * iz[i];
    yn[i] = q.y() * iz[i];
    up[i] = static_cast<float>(K.fx * xn[i] + K.cx);
    vp[i] = static_cast<float>(K.fy * yn[i] + K.cy);
    if (!target.isInside(up[i], vp[i], kProjectionMargin)) {
      return ResidualState::outOfBounds;
    }
    target.prefetch(up[i], vp[i]);
  }
  double sum = 0.;
  for (int k = 0; k < kPatternSize; ++k) {
    const size_t i = static_cast<size_t>(k);
    const Eigen::Vector3f hit = target.interpolate(up[i], vp[i]);
    const double r = static_cast<double>(hit[0]) - pair.b_th - pair.a_th * static_cast<double>(point.patch[k]);
    const double wGrad = static_cast<double>(point.weight[k]);
    sum += wGrad * huberEnergy(r, settings.huberThreshold);
    if (lin) {
      const double absR = std::fabs(r);
      const double wHuber = huberWeight(absR, settings.huberThreshold);
      lin->r[i] = r;
      lin->weight[i] = wGrad * wHuber;
      const double gu = static_cast<double>(hit[1]) * K.fx; // dI/du * fx
      const double gv = static_cast<double>(hit[2]) * K.fy; // dI/dv * fy
      const double rhoIz = rho * iz[i];
      const double x = xn[i], y = yn[i];
      // d(u, v)/d eps for p_t = q / rho under left perturbation: [I, -[p_t]x] then the pinhole projection.
      auto row = lin->J.row(k);
      row[0] = gu * rhoIz;
      row[1] = gv * rhoIz;
      row[2] = -(gu * x + gv * y) * rhoIz;
      row[3] = -gu * x * y - gv * (1. + y * y);
      row[4] = gu * (1. + x * x) + gv * x * y;
      row[5] = -gu * y + gv * x;
      row[6] = -pair.a_th * static_cast<double>(point.patch[k]);
      row[7] = -1.;
      // d(u, v)/d rho: q moves along t_th.
      row[8] = (gu * (t.x() - x * t.z()) + gv * (t.y() - y * t.z())) * iz[i];
    }
  }
  if (lin) {
    lin->energy = sum;
  }
  if (sum > settings.outlierEnergy) {
    return ResidualState::outlier;
  }
  energy = sum;
  return ResidualState::inlier;
}

bool samplePatch(const PyramidLevel &host, double u, double v, double gradientWeightC,
                 std::array<float, kPatternSize> &patch, std::array<float, kPatternSize> &weight)
{
  std::array<float, kPatternSize> p, w;
  const double c2 = gradientWeightC * gradientWeightC;
  for (int k = 0; k < kPatternSize; ++k) {
    const float uk = static_cast<float>(u + kPattern[k][0]);
    const float vk = static_cast<float>(v + kPattern[k][1]);
    if (!host.isInside(uk, vk, 0.f)) {
      return false;
    }
    const Eigen::Vector3f c = host.interpolate(uk, vk);
    p[static_cast<size_t>(k)] = c[0];
    w[static_cast<size_t>(k)] = static_cast<float>(gradientWeight(c2, static_cast<double>(c[1] * c[1] + c[2] * c[2])));
  }
  patch = p;
  weight = w;
  return true;
}
} // namespace hslam
