/*
 * H-SLAM for ViSP.
 */
#include "mapping/InitializationCheck.h"

#include "mapping/TwoViewInitializer.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
/*!
  Agreement bounds. The two-view geometry's own errors at a short baseline are a few tenths of a degree in rotation
  and about a degree in direction (KITTI 06 frames 0-2: 0.25 and 0.5 degree, TwoViewInitializer.h); a wrong map
  gets the motion wrong by more than these bounds (its pose absorbs the wrong structure).
*/
constexpr double kMaxRotationErrorDeg = 1.;
constexpr double kMaxDirectionErrorDeg = 5.;
constexpr double kRadToDeg = 180. / M_PI;
/*!
  The initializer asks for 1 degree of median parallax because its points seed the map; a pose to compare needs less,
  and consecutive keyframes under forward motion rarely have more (KITTI every 4th frame: 0.9-1.0 degree).
*/
constexpr double kMinParallaxDeg = 0.5;
//! A measured direction counts within this many of its standard deviations, when that exceeds the bound.
constexpr double kDirectionSigmas = 3.;

double angleBetweenDeg(const Eigen::Vector3d &x, const Eigen::Vector3d &y)
{
  return std::atan2(x.cross(y).norm(), x.dot(y)) * kRadToDeg;
}
} // namespace

TwoViewPoseCheck checkPoseByTwoViews(const vpHSlamParameters &params, const PinholeIntrinsics &K, const Frame &a,
                                     const Frame &b, const SE3d &bMa)
{
  TwoViewPoseCheck check;
  if (a.raw.getSize() == 0 || a.raw.getWidth() != b.raw.getWidth() || a.raw.getHeight() != b.raw.getHeight() ||
      bMa.translation().norm() <= 0.) {
    return check;
  }
  vpHSlamParameters::Initializer options = params.initializer;
  options.minParallaxDeg = std::min(options.minParallaxDeg, kMinParallaxDeg);
  TwoViewInitializer twoViews(options, K, twoViewOrbOptions(options));
  twoViews.setFirstFrame(a.raw, a.id);
  const bool solved = twoViews.addFrame(b.raw, b.id) == TwoViewInitializer::initialized;
  check.outcome = static_cast<int>(twoViews.lastAttempt().outcome);
  if (!solved) {
    return check;
  }
  const SE3d &measured = twoViews.result().c2Mc1;
  check.measured = true;
  const Eigen::AngleAxisd difference(measured.rotationMatrix().transpose() * bMa.rotationMatrix());
  check.rotationErrorDeg = std::abs(difference.angle()) * kRadToDeg;
  check.directionErrorDeg = angleBetweenDeg(measured.translation(), bMa.translation());
  const double directionBound =
      std::max(kMaxDirectionErrorDeg, kDirectionSigmas * twoViews.result().translationDirSigmaDeg);
  check.agrees = check.rotationErrorDeg <= kMaxRotationErrorDeg && check.directionErrorDeg <= directionBound;
  return check;
}
} // namespace hslam
