/*
 * H-SLAM for ViSP.
 */
// The anchor of a re-used point (mapping/AnchorResidual.h): zero at the stored estimate, and its normal-equation
// blocks against central differences of its energy.
#include "mapping/AnchorResidual.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using namespace hslam;

namespace
{
constexpr double kStep = 1e-6;
constexpr double kTol = 1e-4;

PinholeIntrinsics camera()
{
  return {300., 310., 160., 120.};
}

SE3d pose(double tx, double ty, double tz, double rx, double ry, double rz)
{
  SE3d::Tangent xi;
  xi << tx, ty, tz, rx, ry, rz;
  return SE3d::exp(xi);
}

//! A point seen from a stored keyframe and from a window host, and its anchor at the stored estimate.
struct AnchoredPoint {
  PinholeIntrinsics K = camera();
  SE3d hostMw = pose(0.3, -0.1, 0.05, 0.02, -0.15, 0.01);
  SE3d storedMw = pose(-0.2, 0.05, 0.1, -0.03, 0.1, 0.02);
  double u = 0., v = 0., idepth = 0.;
  PointAnchor anchor;
  AnchoredPoint()
  {
    const Eigen::Vector3d Xw(0.4, -0.3, 2.5);
    const Eigen::Vector3d Ph = hostMw * Xw;
    u = K.fx * Ph.x() / Ph.z() + K.cx;
    v = K.fy * Ph.y() / Ph.z() + K.cy;
    idepth = 1. / Ph.z();
    const Eigen::Vector3d Pa = storedMw * Xw;
    anchor.active = true;
    anchor.anchorMw = storedMw;
    anchor.u = K.fx * Pa.x() / Pa.z() + K.cx;
    anchor.v = K.fy * Pa.y() / Pa.z() + K.cy;
    anchor.idepth = 1. / Pa.z();
    anchor.pixelWeight = 50.;
    anchor.idepthWeight = 4000.;
    anchor.huberPx = 100.; // quadratic in these tests
  }
};
} // namespace

TEST(AnchorResidual, ZeroAtTheStoredEstimate)
{
  const AnchoredPoint s;
  AnchorLinearization lin;
  EXPECT_NEAR(evaluateAnchor(s.K, s.hostMw, s.u, s.v, s.idepth, s.anchor, &lin), 0., 1e-18);
  EXPECT_NEAR(lin.bx.norm(), 0., 1e-9);
  EXPECT_NEAR(lin.br, 0., 1e-9);
  EXPECT_GT(lin.Hrr, 0.);
}

TEST(AnchorResidual, InactiveAnchorCostsNothing)
{
  AnchoredPoint s;
  s.anchor.active = false;
  s.anchor.u += 5.;
  EXPECT_EQ(evaluateAnchor(s.K, s.hostMw, s.u, s.v, s.idepth, s.anchor, nullptr), 0.);
}

TEST(AnchorResidual, GradientAgainstCentralDifferences)
{
  AnchoredPoint s;
  // Move the stored estimate so the residuals are not zero (pixels and inverse depth).
  s.anchor.u += 3.;
  s.anchor.v -= 2.;
  s.anchor.idepth *= 1.1;
  AnchorLinearization lin;
  const double e0 = evaluateAnchor(s.K, s.hostMw, s.u, s.v, s.idepth, s.anchor, &lin);
  ASSERT_GT(e0, 0.);
  // b = J^T W r = 0.5 dE/dx for a quadratic energy.
  for (int k = 0; k < 6; ++k) {
    SE3d::Tangent xi = SE3d::Tangent::Zero();
    xi[k] = kStep;
    const double ep = evaluateAnchor(s.K, SE3d::exp(xi) * s.hostMw, s.u, s.v, s.idepth, s.anchor, nullptr);
    xi[k] = -kStep;
    const double em = evaluateAnchor(s.K, SE3d::exp(xi) * s.hostMw, s.u, s.v, s.idepth, s.anchor, nullptr);
    const double numeric = 0.25 * (ep - em) / kStep;
    EXPECT_NEAR(lin.bx[k], numeric, kTol * std::max(1., std::fabs(numeric))) << "twist component " << k;
  }
  const double ep = evaluateAnchor(s.K, s.hostMw, s.u, s.v, s.idepth + kStep, s.anchor, nullptr);
  const double em = evaluateAnchor(s.K, s.hostMw, s.u, s.v, s.idepth - kStep, s.anchor, nullptr);
  const double numeric = 0.25 * (ep - em) / kStep;
  EXPECT_NEAR(lin.br, numeric, kTol * std::max(1., std::fabs(numeric)));
}

TEST(AnchorResidual, GaussNewtonStepRecoversAShiftedHostPose)
{
  // Several anchored points of one host: Gauss-Newton on the host pose alone (depths held) must bring a shifted
  // host back to where the stored keyframe puts the points.
  const PinholeIntrinsics K = camera();
  const SE3d truthMw = pose(0.3, -0.1, 0.05, 0.02, -0.15, 0.01);
  const SE3d storedMw = pose(-0.2, 0.05, 0.1, -0.03, 0.1, 0.02);
  struct P {
    double u, v, idepth;
    PointAnchor a;
  };
  std::vector<P> points;
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector3d Xw(-0.8 + 0.15 * i, 0.5 * std::sin(i), 2. + 0.3 * std::cos(2. * i));
    const Eigen::Vector3d Ph = truthMw * Xw, Pa = storedMw * Xw;
    P p;
    p.u = K.fx * Ph.x() / Ph.z() + K.cx;
    p.v = K.fy * Ph.y() / Ph.z() + K.cy;
    p.idepth = 1. / Ph.z();
    p.a.active = true;
    p.a.anchorMw = storedMw;
    p.a.u = K.fx * Pa.x() / Pa.z() + K.cx;
    p.a.v = K.fy * Pa.y() / Pa.z() + K.cy;
    p.a.idepth = 1. / Pa.z();
    p.a.pixelWeight = 1.;
    p.a.idepthWeight = 100.;
    p.a.huberPx = 100.;
    points.push_back(p);
  }
  SE3d hostMw = pose(0.02, -0.01, 0.03, 0.01, 0.005, -0.01) * truthMw;
  for (int it = 0; it < 10; ++it) {
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (const P &p : points) {
      // The window point keeps its host pixel and inverse depth, so it moves with the host.
      AnchorLinearization lin;
      evaluateAnchor(K, hostMw, p.u, p.v, p.idepth, p.a, &lin);
      H += lin.Hxx;
      b += lin.bx;
    }
    hostMw = SE3d::exp(-H.ldlt().solve(b)) * hostMw;
  }
  EXPECT_LT((hostMw * truthMw.inverse()).log().norm(), 1e-8);
}

TEST(AnchorResidual, PixelErrorIsTheDistanceToTheStoredPixel)
{
  const AnchoredPoint s;
  EXPECT_NEAR(anchorPixelError(s.K, s.hostMw, s.u, s.v, s.idepth, s.storedMw, s.anchor.u, s.anchor.v), 0., 1e-9);
  EXPECT_NEAR(anchorPixelError(s.K, s.hostMw, s.u, s.v, s.idepth, s.storedMw, s.anchor.u + 3., s.anchor.v - 4.), 5.,
              1e-9);
  // Behind the stored camera: not a usable anchor.
  const SE3d turnedMw = pose(0., 0., 0., 0., M_PI, 0.) * s.storedMw;
  EXPECT_TRUE(std::isinf(anchorPixelError(s.K, s.hostMw, s.u, s.v, s.idepth, turnedMw, s.anchor.u, s.anchor.v)));
}
