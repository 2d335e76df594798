// SO(3) helpers: hat/vee, exp/log over the whole angle range, left/right Jacobians and their inverses.
#include "HSlamTestData.h"
#include "MathTestUtils.h"
#include "math/SO3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using Eigen::Matrix3d;
using Eigen::Vector3d;
using hslam_test::kRoundTripTol;
using hslam_test::maxAbsDiff;
using hslam_test::numericJacobian;

namespace
{
//! Angles that cross every branch: 0, tiny, both sides of the Taylor switch (theta = 1e-3), generic, near pi.
std::vector<double> testAngles()
{
  return {0.0, 1e-9, 1e-6, 0.9e-3, 1.1e-3, 0.3, 1.0, 2.5, M_PI - 1e-3, M_PI - 1e-6};
}
} // namespace

TEST(SO3, HatVeeAndCrossProduct)
{
  for (int i = 0; i < 20; ++i) {
    const Vector3d w = hslam_test::randomVector(3.0);
    const Vector3d v = hslam_test::randomVector(3.0);
    EXPECT_LT(maxAbsDiff(hslam::so3Hat(w) * v, w.cross(v)), 1e-14);
    EXPECT_EQ(hslam::so3Vee(hslam::so3Hat(w)), w);
  }
}

TEST(SO3, ExpIsRotationAndMatchesQuaternionExp)
{
  for (double angle : testAngles()) {
    const Vector3d w = hslam_test::randomRotationVector(angle);
    const Matrix3d R = hslam::so3Exp(w);
    EXPECT_LT(maxAbsDiff(R.transpose() * R, Matrix3d::Identity()), 1e-15) << angle;
    EXPECT_NEAR(R.determinant(), 1.0, 1e-15);
    EXPECT_LT(maxAbsDiff(R, hslam::so3ExpQuaternion(w).toRotationMatrix()), 1e-15) << angle;
    // Rotating the axis leaves it fixed.
    if (angle > 0.0) {
      EXPECT_LT(maxAbsDiff(R * w, w), 1e-15);
    }
  }
}

TEST(SO3, LogExpRoundTripRandom)
{
  double worst = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const Vector3d w = hslam_test::randomRotationVector(hslam_test::uniform(0.0, M_PI - 1e-3));
    worst = std::max(worst, maxAbsDiff(hslam::so3Log(hslam::so3Exp(w)), w));
    worst = std::max(worst, maxAbsDiff(hslam::so3LogQuaternion(hslam::so3ExpQuaternion(w)), w));
  }
  EXPECT_LT(worst, kRoundTripTol);
}

TEST(SO3, SmallAngleRelativeAccuracy)
{
  // At 1e-9 rad the acos-of-trace formula returns 0 (trace rounds to 3); the quaternion path keeps all digits.
  for (int i = 0; i < 10; ++i) {
    const Vector3d w = hslam_test::randomRotationVector(1e-9);
    // The off-diagonal entries of R carry omega with full relative precision, and Eigen's matrix-to-quaternion
    // conversion reads them directly: relative accuracy survives the matrix path too.
    const Vector3d back = hslam::so3Log(hslam::so3Exp(w));
    EXPECT_LT((back - w).norm() / w.norm(), 1e-12);
    const Vector3d backQ = hslam::so3LogQuaternion(hslam::so3ExpQuaternion(w));
    EXPECT_LT((backQ - w).norm() / w.norm(), 1e-12);
  }
  EXPECT_EQ(hslam::so3Log(Matrix3d(Matrix3d::Identity())).norm(), 0.0);
}

TEST(SO3, NearPiRoundTrip)
{
  for (int i = 0; i < 50; ++i) {
    const Vector3d w = hslam_test::randomRotationVector(M_PI - 1e-6);
    const Vector3d back = hslam::so3Log(hslam::so3Exp(w));
    // The quaternion path keeps full accuracy where acos((trace - 1) / 2) would lose ~half the digits.
    EXPECT_LT(maxAbsDiff(back, w), kRoundTripTol) << w.transpose();
    EXPECT_LT(maxAbsDiff(hslam::so3LogQuaternion(hslam::so3ExpQuaternion(w)), w), kRoundTripTol);
  }
}

TEST(SO3, ExactlyPiAboutSeveralAxes)
{
  const std::vector<Vector3d> axes = {Vector3d::UnitX(),
                                      Vector3d::UnitY(),
                                      Vector3d::UnitZ(),
                                      Vector3d(1, 1, 1).normalized(),
                                      Vector3d(1, -2, 3).normalized(),
                                      Vector3d(0, 1, -1).normalized()};
  for (const Vector3d &axis : axes) {
    const Vector3d w = M_PI * axis;
    const Matrix3d R = hslam::so3Exp(w);
    const Vector3d back = hslam::so3Log(R);
    // log is defined up to the sign of the axis at pi: both +w and -w are valid.
    EXPECT_NEAR(back.norm(), M_PI, 1e-12) << axis.transpose();
    EXPECT_LT(std::min(maxAbsDiff(back, w), maxAbsDiff(back, -w)), 1e-12) << axis.transpose();
    EXPECT_LT(maxAbsDiff(hslam::so3Exp(back), R), 1e-12) << axis.transpose();
  }
}

TEST(SO3, LeftAndRightJacobiansAgainstNumeric)
{
  for (double angle : testAngles()) {
    const Vector3d w = hslam_test::randomRotationVector(angle);
    const Matrix3d R = hslam::so3Exp(w);
    // exp(w + d) = exp(Jl d) exp(w)  =>  Jl = d log(exp(w + d) R^T) / dd.
    const auto left = [&](const Vector3d &d) {
      return Vector3d(hslam::so3Log(Matrix3d(hslam::so3Exp(Vector3d(w + d)) * R.transpose())));
    };
    const auto right = [&](const Vector3d &d) {
      return Vector3d(hslam::so3Log(Matrix3d(R.transpose() * hslam::so3Exp(Vector3d(w + d)))));
    };
    const Vector3d zero = Vector3d::Zero();
    EXPECT_LT(maxAbsDiff(hslam::so3LeftJacobian(w), numericJacobian<3, 3>(left, zero)), hslam_test::kNumericJacobianTol)
        << angle;
    EXPECT_LT(maxAbsDiff(hslam::so3RightJacobian(w), numericJacobian<3, 3>(right, zero)),
              hslam_test::kNumericJacobianTol)
        << angle;
    // d log(exp(d) R) / dd = Jl^-1 and d log(R exp(d)) / dd = Jr^-1.
    const auto logLeft = [&](const Vector3d &d) { return Vector3d(hslam::so3Log(Matrix3d(hslam::so3Exp(d) * R))); };
    const auto logRight = [&](const Vector3d &d) { return Vector3d(hslam::so3Log(Matrix3d(R * hslam::so3Exp(d)))); };
    EXPECT_LT(maxAbsDiff(hslam::so3LeftJacobianInverse(w), numericJacobian<3, 3>(logLeft, zero)),
              hslam_test::kNumericJacobianTol)
        << angle;
    EXPECT_LT(maxAbsDiff(hslam::so3RightJacobianInverse(w), numericJacobian<3, 3>(logRight, zero)),
              hslam_test::kNumericJacobianTol)
        << angle;
    EXPECT_LT(maxAbsDiff(hslam::so3LeftJacobian(w) * hslam::so3LeftJacobianInverse(w), Matrix3d::Identity()), 1e-12)
        << angle;
    EXPECT_LT(maxAbsDiff(hslam::so3RightJacobian(w), hslam::so3LeftJacobian(w).transpose()), 1e-15) << angle;
  }
}
