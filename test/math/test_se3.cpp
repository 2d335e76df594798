// SE(3): exp/log round trips over the whole rotation range, group identities, Adjoint, every Jacobian against
// central differences, and ceres::Jet compatibility (automatic derivatives equal the closed forms).
#include "HSlamTestData.h"
#include "MathTestUtils.h"
#include "math/SE3.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include <vector>

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector3d;
using hslam::SE3d;
using hslam_test::kTranslationRange;
using hslam_test::maxAbsDiff;
using hslam_test::numericJacobian;
using hslam_test::randomPose;
using hslam_test::randomTwist;
using hslam_test::twist;
using hslam_test::Vector6d;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

namespace
{
constexpr double kTol = hslam_test::kRoundTripTol;

//! Rotation angles crossing every branch: SO(3) Taylor switch at 1e-3, SE(3) Q switch at 1e-2, near pi.
std::vector<double> testAngles()
{
  return {0.0, 1e-9, 0.9e-3, 1.1e-3, 0.9e-2, 1.1e-2, 0.5, 2.0, M_PI - 1e-3};
}

//! Twist distance modulo the sign ambiguity of log at exactly pi.
double poseDistance(const SE3d &A, const SE3d &B)
{
  return maxAbsDiff(A.matrix(), B.matrix());
}
} // namespace

TEST(SE3, ExpLogRoundTripRandom)
{
  double worst = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const Vector6d xi = randomTwist(hslam_test::uniform(0.0, M_PI - 1e-3));
    worst = std::max(worst, maxAbsDiff(SE3d::exp(xi).log(), xi));
  }
  EXPECT_LT(worst, kTol);
}

TEST(SE3, ExpMatchesMatrixExponential)
{
  for (double angle : testAngles()) {
    const Vector6d xi = randomTwist(angle);
    const Matrix4d expected = SE3d::hat(xi).exp();
    EXPECT_LT(maxAbsDiff(SE3d::exp(xi).matrix(), expected), kTol) << angle;
    EXPECT_EQ(SE3d::vee(SE3d::hat(xi)), xi) << angle;
  }
}

TEST(SE3, SmallAngleRoundTrip)
{
  for (int i = 0; i < 20; ++i) {
    const Vector6d xi = twist(hslam_test::randomVector(kTranslationRange), hslam_test::randomRotationVector(1e-9));
    const Vector6d back = SE3d::exp(xi).log();
    EXPECT_LT(maxAbsDiff(back.head<3>(), xi.head<3>()), kTol);
    EXPECT_LT((back.tail<3>() - xi.tail<3>()).norm() / xi.tail<3>().norm(), 1e-12);
  }
  const Vector6d pureTranslation = twist(Vector3d(1.0, -2.0, 3.0), Vector3d::Zero());
  EXPECT_LT(maxAbsDiff(SE3d::exp(pureTranslation).log(), pureTranslation), 1e-15);
}

TEST(SE3, NearPiRoundTrip)
{
  for (int i = 0; i < 50; ++i) {
    const Vector6d xi = randomTwist(M_PI - 1e-6);
    EXPECT_LT(maxAbsDiff(SE3d::exp(xi).log(), xi), kTol);
  }
}

TEST(SE3, ExactlyPiAboutSeveralAxes)
{
  const std::vector<Vector3d> axes = {Vector3d::UnitX(), Vector3d::UnitY(), Vector3d::UnitZ(),
                                      Vector3d(1, 1, 1).normalized(), Vector3d(-2, 1, 0.5).normalized()};
  for (const Vector3d &axis : axes) {
    const SE3d T = SE3d::exp(twist(Vector3d(0.3, -1.0, 2.0), M_PI * axis));
    const Vector6d back = T.log();
    EXPECT_NEAR(back.tail<3>().norm(), M_PI, 1e-12) << axis.transpose();
    EXPECT_LT(poseDistance(SE3d::exp(back), T), kTol) << axis.transpose();
  }
}

TEST(SE3, ComposeInverseIdentities)
{
  for (int i = 0; i < 100; ++i) {
    const SE3d A = randomPose(), B = randomPose(), C = randomPose();
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    EXPECT_LT(poseDistance(A * A.inverse(), SE3d()), kTol);
    EXPECT_LT(poseDistance(A.inverse() * A, SE3d()), kTol);
    EXPECT_LT(poseDistance((A * B) * C, A * (B * C)), kTol);
    EXPECT_LT(poseDistance((A * B).inverse(), B.inverse() * A.inverse()), kTol);
    EXPECT_LT(maxAbsDiff((A * B).matrix(), A.matrix() * B.matrix()), kTol);
    EXPECT_LT(maxAbsDiff(A * p, (A.matrix() * p.homogeneous()).head<3>()), kTol);
    EXPECT_LT(maxAbsDiff(A.inverse() * (A * p), p), kTol);
  }
}

TEST(SE3, AdjointProperty)
{
  for (int i = 0; i < 100; ++i) {
    const SE3d T = randomPose(), U = randomPose();
    const Vector6d xi = randomTwist(hslam_test::uniform(0.0, 1.0));
    // T exp(xi) T^-1 = exp(Ad_T xi)
    EXPECT_LT(poseDistance(T * SE3d::exp(xi) * T.inverse(), SE3d::exp(T.adjoint() * xi)), 1e-11);
    EXPECT_LT(maxAbsDiff((T * U).adjoint(), T.adjoint() * U.adjoint()), 1e-11);
    EXPECT_LT(maxAbsDiff(T.inverse().adjoint(), Matrix6d(T.adjoint().inverse())), 1e-11);
  }
}

TEST(SE3, ActionJacobiansAgainstNumeric)
{
  for (double angle : testAngles()) {
    const SE3d T = SE3d::exp(randomTwist(angle));
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    const auto leftAct = [&](const Vector6d &d) { return Vector3d(SE3d::exp(d) * T * p); };
    const auto rightAct = [&](const Vector6d &d) { return Vector3d(T * SE3d::exp(d) * p); };
    const auto pointAct = [&](const Vector3d &q) { return Vector3d(T * q); };
    const Vector6d zero = Vector6d::Zero();
    EXPECT_LT(maxAbsDiff(T.jacobianActionLeftPerturbation(p), numericJacobian<3, 6>(leftAct, zero)),
              hslam_test::kNumericJacobianTol)
        << angle;
    EXPECT_LT(maxAbsDiff(T.jacobianActionRightPerturbation(p), numericJacobian<3, 6>(rightAct, zero)),
              hslam_test::kNumericJacobianTol)
        << angle;
    EXPECT_LT(maxAbsDiff(T.jacobianActionPoint(), numericJacobian<3, 3>(pointAct, p)), hslam_test::kNumericJacobianTol);
  }
}

TEST(SE3, LieJacobiansAgainstNumeric)
{
  for (double angle : testAngles()) {
    const Vector6d xi = randomTwist(angle);
    const SE3d T = SE3d::exp(xi);
    const SE3d Tinv = T.inverse();
    const Vector6d zero = Vector6d::Zero();
    // exp(xi + d) = exp(Jl d) exp(xi) and exp(xi + d) = exp(xi) exp(Jr d).
    const auto left = [&](const Vector6d &d) { return Vector6d((SE3d::exp(Vector6d(xi + d)) * Tinv).log()); };
    const auto right = [&](const Vector6d &d) { return Vector6d((Tinv * SE3d::exp(Vector6d(xi + d))).log()); };
    // d log(exp(d) T) = Jl^-1, d log(T exp(d)) = Jr^-1.
    const auto logLeft = [&](const Vector6d &d) { return Vector6d((SE3d::exp(d) * T).log()); };
    const auto logRight = [&](const Vector6d &d) { return Vector6d((T * SE3d::exp(d)).log()); };
    const double tol = hslam_test::kNumericJacobianTol;
    EXPECT_LT(maxAbsDiff(SE3d::leftJacobian(xi), numericJacobian<6, 6>(left, zero)), tol) << angle;
    EXPECT_LT(maxAbsDiff(SE3d::rightJacobian(xi), numericJacobian<6, 6>(right, zero)), tol) << angle;
    EXPECT_LT(maxAbsDiff(T.jacobianLogLeftPerturbation(), numericJacobian<6, 6>(logLeft, zero)), tol) << angle;
    EXPECT_LT(maxAbsDiff(T.jacobianLogRightPerturbation(), numericJacobian<6, 6>(logRight, zero)), tol) << angle;
    EXPECT_LT(maxAbsDiff(SE3d::leftJacobian(xi) * SE3d::leftJacobianInverse(xi), Matrix6d::Identity()), 1e-12);
    EXPECT_LT(maxAbsDiff(SE3d::rightJacobian(xi) * SE3d::rightJacobianInverse(xi), Matrix6d::Identity()), 1e-12);
  }
}

TEST(SE3, PoseGraphResidualJacobians)
{
  // r = log(Z^-1 Ti^-1 Tj); updates Ti <- Ti exp(di), Tj <- Tj exp(dj) (see SE3::jacobianLogRightPerturbation).
  for (int i = 0; i < 20; ++i) {
    const SE3d Ti = randomPose(), Tj = randomPose();
    const SE3d Z = Ti.inverse() * Tj * SE3d::exp(randomTwist(0.2) * 0.1);
    const auto residual = [&](const SE3d &A, const SE3d &B) { return Vector6d((Z.inverse() * A.inverse() * B).log()); };
    const auto fi = [&](const Vector6d &d) { return residual(Ti * SE3d::exp(d), Tj); };
    const auto fj = [&](const Vector6d &d) { return residual(Ti, Tj * SE3d::exp(d)); };
    const SE3d E = Z.inverse() * Ti.inverse() * Tj;
    const Matrix6d Jj = E.jacobianLogRightPerturbation();
    const Matrix6d Ji = -Jj * (Tj.inverse() * Ti).adjoint();
    const Vector6d zero = Vector6d::Zero();
    EXPECT_LT(maxAbsDiff(Jj, numericJacobian<6, 6>(fj, zero)), hslam_test::kNumericJacobianTol);
    EXPECT_LT(maxAbsDiff(Ji, numericJacobian<6, 6>(fi, zero)), hslam_test::kNumericJacobianTol);
  }
}

TEST(SE3, CeresJetDerivativesMatchClosedForms)
{
  using Jet = ceres::Jet<double, 6>;
  using SE3j = hslam::SE3<Jet>;
  using Vector6j = Eigen::Matrix<Jet, 6, 1>;
  for (double angle : testAngles()) {
    const SE3d T = SE3d::exp(randomTwist(angle));
    const SE3j Tj = T.cast<Jet>();
    Vector6j delta;
    for (int k = 0; k < 6; ++k) {
      delta(k) = Jet(0.0, k);
    }
    // Automatic derivative of log(T exp(delta)) at delta = 0: exact, so the tolerance is round-off only.
    const Vector6j r = (Tj * SE3j::exp(delta)).log();
    Matrix6d autoJ;
    for (int row = 0; row < 6; ++row) {
      autoJ.row(row) = r(row).v.transpose();
    }
    EXPECT_LT(maxAbsDiff(autoJ, T.jacobianLogRightPerturbation()), 1e-10) << angle;
    // Automatic derivative of exp(delta) T p: the pose block of a reprojection Jacobian.
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    const Eigen::Matrix<Jet, 3, 1> q = SE3j::exp(delta) * Tj * Eigen::Matrix<Jet, 3, 1>(p.cast<Jet>());
    Eigen::Matrix<double, 3, 6> autoAct;
    for (int row = 0; row < 3; ++row) {
      autoAct.row(row) = q(row).v.transpose();
    }
    EXPECT_LT(maxAbsDiff(autoAct, T.jacobianActionLeftPerturbation(p)), 1e-12) << angle;
  }
}

TEST(SE3, ZeroQuaternionThrows)
{
  EXPECT_THROW(SE3d(Eigen::Quaterniond(0, 0, 0, 0), Vector3d::Zero()), vpHSlamException);
}
