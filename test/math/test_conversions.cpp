// Conversions between the Eigen maths and ViSP: exact round trips, agreement with ViSP's own composition,
// inverse, theta-u and exponential map, and repair of rotations that drifted (matrices read from text).
#include "HSlamTestData.h"
#include "MathTestUtils.h"
#include "math/ViSPConversions.h"

#include <visp3/core/vpColVector.h>
#include <visp3/core/vpExponentialMap.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector3d;
using hslam::SE3d;
using hslam::Sim3d;
using hslam_test::kTranslationRange;
using hslam_test::maxAbsDiff;
using hslam_test::randomPose;
using hslam_test::Vector6d;
using hslam_test::Vector7d;

namespace
{
constexpr double kTol = hslam_test::kRoundTripTol;
// ~45 eps: orthonormality reached by an SVD projection, see DriftedRotationFromTextIsReorthonormalised.
constexpr double kOrthonormalTol = 1e-14;

//! Rounds every entry to `decimals` digits after the point, as a text file written with that precision would.
vpHomogeneousMatrix roundEntries(const vpHomogeneousMatrix &M, int decimals)
{
  const double factor = std::pow(10.0, decimals);
  vpHomogeneousMatrix out = M;
  for (unsigned int i = 0; i < 3; ++i) {
    for (unsigned int j = 0; j < 4; ++j) {
      out[i][j] = std::round(M[i][j] * factor) / factor;
    }
  }
  return out;
}
} // namespace

TEST(Conversions, EigenViSPRoundTripsAreExact)
{
  for (int i = 0; i < 20; ++i) {
    const SE3d T = randomPose();
    const Matrix4d M = T.matrix();
    EXPECT_EQ(hslam::toEigen(hslam::toVpHomogeneousMatrix(M)), M);
    const Matrix3d R = T.rotationMatrix();
    EXPECT_EQ(hslam::toEigen(hslam::toVpRotationMatrix(R)), R);
    EXPECT_EQ(hslam::toEigen(hslam::toVpTranslationVector(T.translation())), T.translation());
    const vpHomogeneousMatrix aMb = hslam::toVpHomogeneousMatrix(T);
    EXPECT_LT(maxAbsDiff(hslam::toSE3(aMb).matrix(), M), kTol);
    EXPECT_LT(maxAbsDiff(hslam::toEigen(hslam::toVpHomogeneousMatrix(hslam::toSE3(aMb))), hslam::toEigen(aMb)), kTol);
    EXPECT_TRUE(vpRotationMatrix(aMb).isARotationMatrix());
  }
}

TEST(Conversions, CompositionInverseAndActionAgreeWithViSP)
{
  for (int i = 0; i < 100; ++i) {
    const SE3d aTb = randomPose(), bTc = randomPose();
    const vpHomogeneousMatrix aMb = hslam::toVpHomogeneousMatrix(aTb), bMc = hslam::toVpHomogeneousMatrix(bTc);
    EXPECT_LT(maxAbsDiff(hslam::toEigen(aMb * bMc), (aTb * bTc).matrix()), kTol);
    EXPECT_LT(maxAbsDiff(hslam::toEigen(aMb.inverse()), aTb.inverse().matrix()), kTol);
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    vpColVector ph(4);
    ph[0] = p(0);
    ph[1] = p(1);
    ph[2] = p(2);
    ph[3] = 1.0;
    const vpColVector q = aMb * ph;
    EXPECT_LT(maxAbsDiff(Vector3d(q[0], q[1], q[2]), aTb * p), kTol);
  }
}

TEST(Conversions, LogAgreesWithViSPThetaU)
{
  // Away from pi theta-u is unique; ViSP computes it from sin/cos of the antisymmetric part and the trace.
  double worst = 0.0;
  for (int i = 0; i < 500; ++i) {
    const Vector3d w = hslam_test::randomRotationVector(hslam_test::uniform(0.0, M_PI - 1e-2));
    const vpThetaUVector tu(hslam::toVpRotationMatrix(hslam::so3Exp(w)));
    worst = std::max(worst, maxAbsDiff(hslam::toEigen(tu), hslam::so3Log(Matrix3d(hslam::so3Exp(w)))));
  }
  EXPECT_LT(worst, kTol);
  // ViSP's rotation from theta-u agrees with so3Exp.
  for (int i = 0; i < 100; ++i) {
    const Vector3d w = hslam_test::randomRotationVector(hslam_test::uniform(0.0, M_PI));
    const vpRotationMatrix R(vpThetaUVector(w(0), w(1), w(2)));
    EXPECT_LT(maxAbsDiff(hslam::toEigen(R), hslam::so3Exp(w)), kTol);
  }
}

TEST(Conversions, ExpLogAgreeWithViSPExponentialMap)
{
  // vpExponentialMap takes the velocity twist (v, w) applied for 1 s: the same ordering as SE3's tangent.
  for (int i = 0; i < 100; ++i) {
    const Vector6d xi = hslam_test::randomTwist(hslam_test::uniform(0.0, M_PI - 1e-2));
    vpColVector v(6);
    for (unsigned int k = 0; k < 6; ++k) {
      v[k] = xi(k);
    }
    const vpHomogeneousMatrix M = vpExponentialMap::direct(v);
    EXPECT_LT(maxAbsDiff(hslam::toEigen(M), SE3d::exp(xi).matrix()), 1e-10);
    const vpColVector back = vpExponentialMap::inverse(M);
    Vector6d backXi;
    for (unsigned int k = 0; k < 6; ++k) {
      backXi(k) = back[k];
    }
    EXPECT_LT(maxAbsDiff(backXi, SE3d::exp(xi).log()), 1e-10);
  }
}

TEST(Conversions, DriftedRotationFromTextIsReorthonormalised)
{
  for (int decimals : {6, 4}) {
    for (int i = 0; i < 50; ++i) {
      const vpHomogeneousMatrix exact = hslam::toVpHomogeneousMatrix(randomPose());
      const vpHomogeneousMatrix read = roundEntries(exact, decimals);
      const double rounding = 0.5 * std::pow(10.0, -decimals);
      const vpHomogeneousMatrix fixed = hslam::orthonormalize(read);
      const Matrix3d R = hslam::toEigen(fixed).topLeftCorner<3, 3>();
      // Machine precision: U diag V^T from a Jacobi SVD, then R^T R, accumulate ~10 roundings of O(1) numbers.
      EXPECT_LT(maxAbsDiff(R.transpose() * R, Matrix3d::Identity()), kOrthonormalTol);
      EXPECT_NEAR(R.determinant(), 1.0, kOrthonormalTol);
      EXPECT_TRUE(vpRotationMatrix(fixed).isARotationMatrix());
      // The repaired rotation stays within the rounding of the exact one (a few entries' worth).
      EXPECT_LT(maxAbsDiff(hslam::toEigen(fixed), hslam::toEigen(exact)), 3.0 * rounding) << decimals;
      // Translation is untouched.
      const Vector3d tFixed = hslam::toEigen(fixed).topRightCorner<3, 1>();
      const Vector3d tRead = hslam::toEigen(read).topRightCorner<3, 1>();
      EXPECT_EQ(tFixed, tRead);
      const SE3d T = hslam::toSE3(read);
      EXPECT_LT(maxAbsDiff(T.matrix(), hslam::toEigen(fixed)), kTol);
    }
  }
}

TEST(Conversions, NonRotationsAreRejected)
{
  const vpHomogeneousMatrix good = hslam::toVpHomogeneousMatrix(randomPose());
  vpHomogeneousMatrix scaled = good;
  for (unsigned int i = 0; i < 3; ++i) {
    for (unsigned int j = 0; j < 3; ++j) {
      scaled[i][j] *= 1.1;
    }
  }
  EXPECT_THROW(hslam::toSE3(scaled), vpHSlamException);
  vpHomogeneousMatrix reflected = good;
  for (unsigned int j = 0; j < 3; ++j) {
    reflected[2][j] = -reflected[2][j];
  }
  EXPECT_THROW(hslam::orthonormalize(reflected), vpHSlamException);
  vpHomogeneousMatrix badRow = good;
  badRow[3][0] = 0.5;
  EXPECT_THROW(hslam::toSE3(badRow), vpHSlamException);
  vpHomogeneousMatrix notFinite = good;
  notFinite[0][0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(hslam::toSE3(notFinite), vpHSlamException);
  EXPECT_THROW(hslam::toSim3(good, 0.0), vpHSlamException);
  EXPECT_THROW(hslam::toSim3(good, -2.0), vpHSlamException);
}

TEST(Conversions, Sim3RoundTripAndActionAgreeWithViSP)
{
  for (int i = 0; i < 50; ++i) {
    const SE3d aTb = randomPose();
    const double scale = std::exp(hslam_test::uniform(-2.0, 2.0));
    const vpHomogeneousMatrix aMb = hslam::toVpHomogeneousMatrix(aTb);
    const Sim3d aSb = hslam::toSim3(aMb, scale);
    double scaleBack = 0.0;
    const vpHomogeneousMatrix aMbBack = hslam::toVpHomogeneousMatrix(aSb, scaleBack);
    EXPECT_NEAR(scaleBack, scale, 1e-15 * scale);
    EXPECT_LT(maxAbsDiff(hslam::toEigen(aMbBack), hslam::toEigen(aMb)), kTol);
    // s R p + t computed with ViSP types.
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    const vpColVector pv = hslam::toVpTranslationVector(p);
    const vpColVector Rp = vpRotationMatrix(aMb) * pv;
    const vpTranslationVector t(aMb);
    const Vector3d expected(scale * Rp[0] + t[0], scale * Rp[1] + t[1], scale * Rp[2] + t[2]);
    EXPECT_LT(maxAbsDiff(aSb * p, expected), 1e-11);
    // Sim3 log/exp survives the round trip through ViSP.
    Vector7d xi = aSb.log();
    EXPECT_LT(maxAbsDiff(hslam::toSim3(aMbBack, scaleBack).log(), xi), 1e-10);
  }
}
