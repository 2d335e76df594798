/*
 * H-SLAM for ViSP.
 */
/*!
  \file SO3.h
  \brief Rotation-group helpers (hat/vee, exp, log, left/right Jacobians), templated on the scalar type.

  Internal header (namespace hslam), header-only, no allocation: fixed-size Eigen types only. Every function is a
  template on Scalar so that ceres::Jet can flow through it (pose-graph optimisation with automatic
  differentiation). For that reason:
  - maths functions are called unqualified after `using std::xxx`, so argument-dependent lookup finds ceres::sin,
    ceres::sqrt, ... for Jets;
  - small-angle branches test theta^2 (never theta = sqrt(theta^2), whose derivative is infinite at 0) and use
    Taylor series, so both the value and its derivative are exact at the identity.

  The free functions deduce Scalar from their argument, so pass Eigen::Matrix objects, not expressions:
  so3Exp(Eigen::Vector3d(a + b)), or name the scalar: so3Exp<double>(a + b).

  Conventions (shared by SE3.h and Sim3.h):
  - a rotation vector omega has angle theta = |omega| (radians) and axis omega / theta;
  - exp(omega) = I + sin(theta)/theta [omega]x + (1 - cos(theta))/theta^2 [omega]x^2 (Rodrigues);
  - left Jacobian Jl(omega): exp(omega + d) ~= exp(Jl(omega) d) exp(omega);
    right Jacobian Jr(omega) = Jl(-omega) = Jl(omega)^T: exp(omega + d) ~= exp(omega) exp(Jr(omega) d)
    (Barfoot, "State Estimation for Robotics", 2017, sec. 7.1).
*/
#ifndef HSLAM_MATH_SO3_H
#define HSLAM_MATH_SO3_H

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>

namespace hslam
{
/*!
  Below this squared angle (rad^2) the closed forms are replaced by their Taylor series (kept to the theta^4
  term): they would divide 0 by 0 at the identity, and a Jet needs the series to carry the right derivative there.
  At theta^2 = 1e-6 the first dropped term is below theta^6 / 5040 ~ 2e-22, far under double precision, while
  the remaining cancelling closed form, (theta - sin theta) / theta^3, loses ~eps / theta^2 on a term scaled by
  theta^2: both sides of the switch agree to ~1e-16 absolute.
*/
constexpr double kSO3SmallAngleSq = 1e-6;

/*!
  (1 - cos t) / t^2 written as (sin(t/2) / (t/2))^2 / 2: the direct form cancels (error ~eps / t^2, and it
  multiplies [w]x of size t in the Jacobians, so eps / t absolute), the half-angle form does not. Requires t > 0.
*/
template <typename Scalar> Scalar so3OneMinusCosOverThetaSq(const Scalar &theta)
{
  using std::sin;
  const Scalar halfTheta = Scalar(0.5) * theta;
  const Scalar sinc = sin(halfTheta) / halfTheta;
  return Scalar(0.5) * sinc * sinc;
}

//! Cross-product matrix [w]x, so that hat(w) * v = w x v.
template <typename Scalar> Eigen::Matrix<Scalar, 3, 3> so3Hat(const Eigen::Matrix<Scalar, 3, 1> &w)
{
  Eigen::Matrix<Scalar, 3, 3> W;
  const Scalar zero(0);
  W << zero, -w(2), w(1), w(2), zero, -w(0), -w(1), w(0), zero;
  return W;
}

//! Inverse of so3Hat: the vector of a skew-symmetric matrix. The symmetric part of W, if any, is ignored.
template <typename Scalar> Eigen::Matrix<Scalar, 3, 1> so3Vee(const Eigen::Matrix<Scalar, 3, 3> &W)
{
  const Scalar half(0.5);
  return Eigen::Matrix<Scalar, 3, 1>(half * (W(2, 1) - W(1, 2)), half * (W(0, 2) - W(2, 0)),
                                     half * (W(1, 0) - W(0, 1)));
}

/*!
  Exponential map of SO(3) as a rotation matrix, by Rodrigues' formula.
  Small angles use A = sin(t)/t ~ 1 - t^2/6 + t^4/120 and B = (1 - cos t)/t^2 ~ 1/2 - t^2/24 + t^4/720.
*/
template <typename Scalar> Eigen::Matrix<Scalar, 3, 3> so3Exp(const Eigen::Matrix<Scalar, 3, 1> &omega)
{
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar thetaSq = omega.squaredNorm();
  Scalar A, B;
  if (thetaSq < Scalar(kSO3SmallAngleSq)) {
    A = Scalar(1) - thetaSq / Scalar(6) + thetaSq * thetaSq / Scalar(120);
    B = Scalar(0.5) - thetaSq / Scalar(24) + thetaSq * thetaSq / Scalar(720);
  } else {
    const Scalar theta = sqrt(thetaSq);
    A = sin(theta) / theta;
    B = so3OneMinusCosOverThetaSq(theta);
  }
  const Eigen::Matrix<Scalar, 3, 3> W = so3Hat(omega);
  return Eigen::Matrix<Scalar, 3, 3>::Identity() + A * W + B * (W * W);
}

/*!
  Exponential map of SO(3) as a unit quaternion q = (cos(t/2), sin(t/2)/t * omega).
  Small angles: sin(t/2)/t ~ 1/2 - t^2/48 + t^4/3840, cos(t/2) ~ 1 - t^2/8 + t^4/384.
*/
template <typename Scalar> Eigen::Quaternion<Scalar> so3ExpQuaternion(const Eigen::Matrix<Scalar, 3, 1> &omega)
{
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar thetaSq = omega.squaredNorm();
  Scalar w, k;
  if (thetaSq < Scalar(kSO3SmallAngleSq)) {
    w = Scalar(1) - thetaSq / Scalar(8) + thetaSq * thetaSq / Scalar(384);
    k = Scalar(0.5) - thetaSq / Scalar(48) + thetaSq * thetaSq / Scalar(3840);
  } else {
    const Scalar theta = sqrt(thetaSq);
    const Scalar halfTheta = Scalar(0.5) * theta;
    w = cos(halfTheta);
    k = sin(halfTheta) / theta;
  }
  Eigen::Quaternion<Scalar> q(w, k * omega(0), k * omega(1), k * omega(2));
  // The Taylor branch is exact to ~1e-22; renormalising removes the last rounding so q stays unit.
  q.normalize();
  return q;
}

/*!
  Logarithm of a unit quaternion: the rotation vector omega with |omega| in [0, pi].

  Robust over the whole range (unlike acos((trace - 1) / 2), which loses half the digits near 0 and near pi):
  theta = 2 atan2(|v|, w) after choosing the sign of q with w >= 0, and omega = theta / |v| * v. Near theta = 0,
  2 atan(n / w) / n ~ 2 / w (1 - n^2 / (3 w^2)). At theta = pi exactly (w = 0) the result has norm pi; either
  sign of the axis is a valid logarithm.
*/
template <typename Scalar> Eigen::Matrix<Scalar, 3, 1> so3LogQuaternion(const Eigen::Quaternion<Scalar> &qIn)
{
  using std::atan2;
  using std::sqrt;
  // q and -q are the same rotation; w >= 0 picks the representative whose angle lies in [0, pi].
  const Scalar sign = qIn.w() < Scalar(0) ? Scalar(-1) : Scalar(1);
  const Scalar w = sign * qIn.w();
  const Eigen::Matrix<Scalar, 3, 1> v = sign * qIn.vec();
  const Scalar nSq = v.squaredNorm();
  Scalar factor;
  // sin(theta/2)^2 = nSq, so the same threshold as the other small-angle branches (scaled by 1/4).
  if (nSq < Scalar(0.25 * kSO3SmallAngleSq)) {
    // 2 atan(x) / n with x = n / w: 2/w (1 - x^2/3 + x^4/5); the next term, x^6/7 ~ 3e-21, is dropped.
    const Scalar xSq = nSq / (w * w);
    factor = Scalar(2) / w * (Scalar(1) - xSq / Scalar(3) + xSq * xSq / Scalar(5));
  } else {
    const Scalar n = sqrt(nSq);
    factor = Scalar(2) * atan2(n, w) / n;
  }
  return factor * v;
}

/*!
  Logarithm of a rotation matrix (assumed orthonormal with det +1), through its quaternion: Eigen converts with
  Shepperd's method (largest diagonal pivot), which stays accurate near theta = pi where the antisymmetric part
  of R vanishes.
*/
template <typename Scalar> Eigen::Matrix<Scalar, 3, 1> so3Log(const Eigen::Matrix<Scalar, 3, 3> &R)
{
  return so3LogQuaternion(Eigen::Quaternion<Scalar>(R));
}

/*!
  Left Jacobian of SO(3) (Barfoot 2017, sec. 7.1):
  Jl = I + (1 - cos t)/t^2 [w]x + (t - sin t)/t^3 [w]x^2.
  Small angles: (1 - cos t)/t^2 ~ 1/2 - t^2/24 + t^4/720, (t - sin t)/t^3 ~ 1/6 - t^2/120 + t^4/5040.
  It is also the V matrix of SE(3): the translation of exp(upsilon, omega) is Jl(omega) upsilon.
*/
template <typename Scalar> Eigen::Matrix<Scalar, 3, 3> so3LeftJacobian(const Eigen::Matrix<Scalar, 3, 1> &omega)
{
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar thetaSq = omega.squaredNorm();
  Scalar B, C;
  if (thetaSq < Scalar(kSO3SmallAngleSq)) {
    B = Scalar(0.5) - thetaSq / Scalar(24) + thetaSq * thetaSq / Scalar(720);
    C = Scalar(1) / Scalar(6) - thetaSq / Scalar(120) + thetaSq * thetaSq / Scalar(5040);
  } else {
    const Scalar theta = sqrt(thetaSq);
    B = so3OneMinusCosOverThetaSq(theta);
    C = (theta - sin(theta)) / (thetaSq * theta);
  }
  const Eigen::Matrix<Scalar, 3, 3> W = so3Hat(omega);
  return Eigen::Matrix<Scalar, 3, 3>::Identity() + B * W + C * (W * W);
}

/*!
  Inverse of the left Jacobian of SO(3) (Barfoot 2017, sec. 7.1, written with cot):
  Jl^-1 = I - 1/2 [w]x + (1 - (t/2) cot(t/2)) / t^2 [w]x^2. Singular only at t = 2 pi, so it is well defined on
  the whole range of so3Log (t <= pi). Small angles: (1 - (t/2) cot(t/2)) / t^2 ~ 1/12 + t^2/720 + t^4/30240.
*/
template <typename Scalar> Eigen::Matrix<Scalar, 3, 3> so3LeftJacobianInverse(const Eigen::Matrix<Scalar, 3, 1> &omega)
{
  using std::cos;
  using std::sin;
  using std::sqrt;
  const Scalar thetaSq = omega.squaredNorm();
  Scalar D;
  if (thetaSq < Scalar(kSO3SmallAngleSq)) {
    D = Scalar(1) / Scalar(12) + thetaSq / Scalar(720) + thetaSq * thetaSq / Scalar(30240);
  } else {
    const Scalar theta = sqrt(thetaSq);
    const Scalar halfTheta = Scalar(0.5) * theta;
    D = (Scalar(1) - halfTheta * cos(halfTheta) / sin(halfTheta)) / thetaSq;
  }
  const Eigen::Matrix<Scalar, 3, 3> W = so3Hat(omega);
  return Eigen::Matrix<Scalar, 3, 3>::Identity() - Scalar(0.5) * W + D * (W * W);
}

//! Right Jacobian of SO(3): Jr(omega) = Jl(-omega) = Jl(omega)^T.
template <typename Scalar> Eigen::Matrix<Scalar, 3, 3> so3RightJacobian(const Eigen::Matrix<Scalar, 3, 1> &omega)
{
  return so3LeftJacobian<Scalar>(-omega);
}

//! Inverse of the right Jacobian of SO(3): Jr^-1(omega) = Jl^-1(-omega). d log(R exp(d)) / d d at d = 0.
template <typename Scalar> Eigen::Matrix<Scalar, 3, 3> so3RightJacobianInverse(const Eigen::Matrix<Scalar, 3, 1> &omega)
{
  return so3LeftJacobianInverse<Scalar>(-omega);
}

} // namespace hslam

#endif
