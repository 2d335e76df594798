// Shared helpers of the math tests: seeded random samples (vectors, twists, poses), tolerances and central numeric
// differences.
#ifndef HSLAM_TEST_MATH_TEST_UTILS_H
#define HSLAM_TEST_MATH_TEST_UTILS_H

#include "math/Sim3.h"

#include <Eigen/Core>

#include <cmath>
#include <random>

namespace hslam_test
{
/*!
  Step of the central differences. The error of (f(x+h) - f(x-h)) / 2h is h^2 |f'''| / 6 (truncation, ~2e-13
  for the O(1..10) third derivatives met here) plus ~eps |f| / h (rounding, ~2e-10 * |f|, |f| <= ~20): both stay
  well under kNumericJacobianTol.
*/
constexpr double kNumericStep = 1e-6;
//! Tolerance of an analytic Jacobian against central differences (see kNumericStep: worst case ~5e-9).
constexpr double kNumericJacobianTol = 1e-7;

//! Round trips and identities in double: a few dozen roundings of O(1..10) numbers.
constexpr double kRoundTripTol = 1e-12;
//! Random translations are drawn in [-kTranslationRange, kTranslationRange] metres per axis.
constexpr double kTranslationRange = 5.0;

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Vector7d = Eigen::Matrix<double, 7, 1>;

//! Fixed seed: every run draws the same samples.
inline std::mt19937 &rng()
{
  static std::mt19937 generator(20261121u);
  return generator;
}

inline double uniform(double lo, double hi)
{
  return std::uniform_real_distribution<double>(lo, hi)(rng());
}

inline Eigen::Vector3d randomVector(double halfRange)
{
  return Eigen::Vector3d(uniform(-halfRange, halfRange), uniform(-halfRange, halfRange),
                         uniform(-halfRange, halfRange));
}

inline Eigen::Vector3d randomUnitVector()
{
  Eigen::Vector3d v;
  do {
    v = randomVector(1.0);
  } while (v.norm() < 0.1);
  return v.normalized();
}

//! Rotation vector with a given angle (radians) about a random axis.
inline Eigen::Vector3d randomRotationVector(double angle)
{
  return angle * randomUnitVector();
}

//! SE(3) tangent (upsilon, omega): translation part first, as SE3d::exp() takes it.
inline Vector6d twist(const Eigen::Vector3d &upsilon, const Eigen::Vector3d &omega)
{
  Vector6d xi;
  xi << upsilon, omega;
  return xi;
}

//! Random SE(3) tangent whose rotation has the given angle (radians).
inline Vector6d randomTwist(double angle)
{
  return twist(randomVector(kTranslationRange), randomRotationVector(angle));
}

//! Random rigid transform, rotation angle drawn in [0, maxAngle].
inline hslam::SE3d randomPose(double maxAngle = M_PI)
{
  return hslam::SE3d::exp(randomTwist(uniform(0.0, maxAngle)));
}

//! Sim(3) tangent (upsilon, omega, sigma = log scale).
inline Vector7d tangent(const Eigen::Vector3d &upsilon, const Eigen::Vector3d &omega, double sigma)
{
  Vector7d xi;
  xi << upsilon, omega, sigma;
  return xi;
}

//! Random Sim(3) tangent with the given rotation angle (radians) and log-scale.
inline Vector7d randomTangent(double angle, double sigma)
{
  return tangent(randomVector(kTranslationRange), randomRotationVector(angle), sigma);
}

/*!
  Central-difference Jacobian of f : R^N -> R^M at x (f returns an Eigen::Matrix<double, M, 1>).
*/
template <int M, int N, typename F>
Eigen::Matrix<double, M, N> numericJacobian(const F &f, const Eigen::Matrix<double, N, 1> &x, double h = kNumericStep)
{
  Eigen::Matrix<double, M, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    J.col(i) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

//! Largest absolute entry of A - B.
template <typename DA, typename DB> double maxAbsDiff(const Eigen::MatrixBase<DA> &A, const Eigen::MatrixBase<DB> &B)
{
  return (A - B).cwiseAbs().maxCoeff();
}

} // namespace hslam_test

#endif
