// Sim(3): Strasdat's exp/log in every (rotation, log-scale) regime, group identities, Adjoint, Jacobians,
// agreement with SE(3) at unit scale and ceres::Jet compatibility.
#include "HSlamTestData.h"
#include "MathTestUtils.h"
#include "math/Sim3.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include <vector>

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector3d;
using hslam::SE3d;
using hslam::Sim3d;
using hslam_test::kTranslationRange;
using hslam_test::maxAbsDiff;
using hslam_test::numericJacobian;
using hslam_test::randomTangent;
using hslam_test::tangent;
using hslam_test::Vector7d;
using Matrix7d = Eigen::Matrix<double, 7, 7>;

namespace
{
constexpr double kTol = hslam_test::kRoundTripTol;

Sim3d randomSim3()
{
  return Sim3d::exp(randomTangent(hslam_test::uniform(0.0, M_PI), hslam_test::uniform(-1.0, 1.0)));
}

double distance(const Sim3d &A, const Sim3d &B)
{
  return maxAbsDiff(A.matrix(), B.matrix());
}

//! Angles around the Sim3 small-angle switch (theta^2 = 1e-10) and the SO(3) one (1e-3), generic, near pi.
std::vector<double> testAngles()
{
  return {0.0, 1e-9, 0.9e-5, 1.1e-5, 0.9e-3, 1.1e-3, 0.7, 2.9, M_PI - 1e-6};
}
//! Log-scales around the small-sigma switch (1e-3), tiny, and large.
std::vector<double> testSigmas()
{
  return {0.0, 1e-9, -1e-6, 0.9e-3, -1.1e-3, 0.2, -0.8, 2.0};
}
} // namespace

TEST(Sim3, ExpMatchesMatrixExponentialInEveryRegime)
{
  for (double angle : testAngles()) {
    for (double sigma : testSigmas()) {
      const Vector7d xi = randomTangent(angle, sigma);
      const Matrix4d expected = Sim3d::hat(xi).exp();
      EXPECT_LT(maxAbsDiff(Sim3d::exp(xi).matrix(), expected) / expected.cwiseAbs().maxCoeff(), kTol)
          << "angle " << angle << " sigma " << sigma;
      EXPECT_LT(maxAbsDiff(Sim3d::vee(Sim3d::hat(xi)), xi), 1e-15);
    }
  }
}

TEST(Sim3, LogExpRoundTripInEveryRegime)
{
  for (double angle : testAngles()) {
    for (double sigma : testSigmas()) {
      const Vector7d xi = randomTangent(angle, sigma);
      const Vector7d back = Sim3d::exp(xi).log();
      EXPECT_LT(maxAbsDiff(back, xi), kTol) << "angle " << angle << " sigma " << sigma;
      if (angle > 0.0 && angle < 1e-6) {
        EXPECT_LT((back.segment<3>(3) - xi.segment<3>(3)).norm() / angle, 1e-12);
      }
      if (sigma != 0.0 && std::abs(sigma) < 1e-5) {
        EXPECT_LT(std::abs(back(6) - sigma) / std::abs(sigma), 1e-6);
      }
    }
  }
}

TEST(Sim3, LogExpRoundTripRandom)
{
  double worst = 0.0;
  for (int i = 0; i < 1000; ++i) {
    const Vector7d xi = randomTangent(hslam_test::uniform(0.0, M_PI - 1e-3), hslam_test::uniform(-2.0, 2.0));
    worst = std::max(worst, maxAbsDiff(Sim3d::exp(xi).log(), xi));
  }
  EXPECT_LT(worst, kTol);
}

TEST(Sim3, UnitScaleAgreesWithSE3)
{
  for (double angle : testAngles()) {
    const Vector7d xi = randomTangent(angle, 0.0);
    const SE3d T = SE3d::exp(xi.head<6>());
    EXPECT_LT(maxAbsDiff(Sim3d::exp(xi).matrix(), T.matrix()), kTol);
    EXPECT_LT(maxAbsDiff(Sim3d(T, 1.0).log().head<6>(), T.log()), kTol);
  }
}

TEST(Sim3, ComposeInverseActIdentities)
{
  for (int i = 0; i < 100; ++i) {
    const Sim3d A = randomSim3(), B = randomSim3(), C = randomSim3();
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    EXPECT_LT(distance(A * A.inverse(), Sim3d()), 1e-11);
    EXPECT_LT(distance((A * B) * C, A * (B * C)), 1e-10);
    EXPECT_LT(distance((A * B).inverse(), B.inverse() * A.inverse()), 1e-10);
    EXPECT_LT(maxAbsDiff((A * B).matrix(), A.matrix() * B.matrix()), 1e-10);
    EXPECT_LT(maxAbsDiff(A * p, Vector3d(A.scale() * (A.rotationMatrix() * p) + A.translation())), 1e-11);
    EXPECT_LT(maxAbsDiff(A * p, (A.matrix() * p.homogeneous()).head<3>()), 1e-11);
    EXPECT_LT(maxAbsDiff(A.inverse() * (A * p), p), 1e-11);
    EXPECT_NEAR((A * B).scale(), A.scale() * B.scale(), 1e-14);
  }
}

TEST(Sim3, AdjointProperty)
{
  for (int i = 0; i < 100; ++i) {
    const Sim3d S = randomSim3(), U = randomSim3();
    const Vector7d xi = randomTangent(hslam_test::uniform(0.0, 1.0), hslam_test::uniform(-0.5, 0.5));
    const Sim3d lhs = S * Sim3d::exp(xi) * S.inverse();
    const Sim3d rhs = Sim3d::exp(S.adjoint() * xi);
    EXPECT_LT(distance(lhs, rhs) / lhs.matrix().cwiseAbs().maxCoeff(), 1e-11);
    EXPECT_LT(maxAbsDiff((S * U).adjoint(), S.adjoint() * U.adjoint()), 1e-10);
  }
}

TEST(Sim3, ActionJacobiansAgainstNumeric)
{
  for (double angle : testAngles()) {
    const Sim3d S = Sim3d::exp(randomTangent(angle, hslam_test::uniform(-0.5, 0.5)));
    const Vector3d p = hslam_test::randomVector(kTranslationRange);
    const auto leftAct = [&](const Vector7d &d) { return Vector3d(Sim3d::exp(d) * S * p); };
    const auto pointAct = [&](const Vector3d &q) { return Vector3d(S * q); };
    EXPECT_LT(maxAbsDiff(S.jacobianActionLeftPerturbation(p), numericJacobian<3, 7>(leftAct, Vector7d::Zero())),
              hslam_test::kNumericJacobianTol)
        << angle;
    EXPECT_LT(maxAbsDiff(S.jacobianActionPoint(), numericJacobian<3, 3>(pointAct, p)), hslam_test::kNumericJacobianTol);
  }
}

TEST(Sim3, CeresJetAtIdentityAndRoundTrip)
{
  using Jet = ceres::Jet<double, 7>;
  using Sim3j = hslam::Sim3<Jet>;
  using Vector7j = Eigen::Matrix<Jet, 7, 1>;
  // exp at 0 goes through both small-angle and small-sigma branches: d exp(d) p / dd must be [I, -[p]x, p].
  Vector7j delta;
  for (int k = 0; k < 7; ++k) {
    delta(k) = Jet(0.0, k);
  }
  const Vector3d p(0.4, -1.2, 2.5);
  const Eigen::Matrix<Jet, 3, 1> q = Sim3j::exp(delta) * Eigen::Matrix<Jet, 3, 1>(p.cast<Jet>());
  Eigen::Matrix<double, 3, 7> autoJ;
  for (int row = 0; row < 3; ++row) {
    autoJ.row(row) = q(row).v.transpose();
  }
  EXPECT_LT(maxAbsDiff(autoJ, Sim3d().jacobianActionLeftPerturbation(p)), 1e-15);
  // log(exp(x)) = x carries the identity Jacobian through every branch.
  for (double angle : {0.0, 1e-9, 0.5}) {
    for (double sigma : {0.0, 1e-9, 0.3}) {
      const Vector7d x = randomTangent(angle, sigma);
      Vector7j xj;
      for (int k = 0; k < 7; ++k) {
        xj(k) = Jet(x(k), k);
      }
      const Vector7j back = Sim3j::exp(xj).log();
      Matrix7d dBack;
      for (int row = 0; row < 7; ++row) {
        dBack.row(row) = back(row).v.transpose();
        EXPECT_NEAR(back(row).a, x(row), 1e-11);
      }
      EXPECT_LT(maxAbsDiff(dBack, Matrix7d::Identity()), 1e-9) << "angle " << angle << " sigma " << sigma;
    }
  }
}

TEST(Sim3, NonPositiveScaleThrows)
{
  EXPECT_THROW(Sim3d(Eigen::Quaterniond::Identity(), Vector3d::Zero(), 0.0), vpHSlamException);
  EXPECT_THROW(Sim3d(Eigen::Quaterniond::Identity(), Vector3d::Zero(), -1.0), vpHSlamException);
}
