/*
 * H-SLAM for ViSP.
 */
/*!
  \file Sim3.h
  \brief Similarity transform Sim(3) on Eigen, templated on the scalar type (double, ceres::Jet), no allocation.

  A Sim(3) element S = [s R, t; 0, 1] maps p to s R p + t (loop closure and pose-graph optimisation of a
  monocular map, where scale drifts). Tangent vectors are 7-vectors (upsilon, omega, sigma): translation part,
  rotation vector, log-scale, in that order; every 7x7 matrix below uses that order.

  The exponential follows H. Strasdat, "Local Accuracy and Global Consistency for Efficient Visual SLAM",
  PhD thesis, Imperial College London 2012 (and Strasdat, Montiel, Davison, "Scale Drift-Aware Large Scale
  Monocular SLAM", RSS 2010):
  exp(upsilon, omega, sigma) = (R = exp(omega), s = e^sigma, t = W upsilon) with
  W = integral_0^1 e^(sigma tau) exp(tau [omega]x) d tau = A [omega]x + B [omega]x^2 + C I.
*/
#ifndef HSLAM_MATH_SIM3_H
#define HSLAM_MATH_SIM3_H

#include "math/SE3.h"

#include <Eigen/LU>

#include <string>

namespace hslam
{
/*!
  Rotation angles with theta^2 below this (rad^2) use the theta -> 0 limit of A and B (exact in sigma). The
  dropped terms are O(theta^2) relative (A's first one is theta^2/24) on a term of size A theta |upsilon|, i.e.
  below 1e-10 * 1e-5 / 24 ~ 4e-17 |upsilon|.
*/
constexpr double kSim3SmallAngleSq = 1e-10;
/*!
  |log-scale| below this uses the sigma-Taylor series of A, B, C (to sigma^4: first dropped term sigma^5 / 720 ~
  1.4e-18). Above it, the closed forms' cancellation ((sigma - 1) e^sigma + 1 ~ sigma^2 / 2) costs at most
  eps / sigma^2 ~ 2e-10 relative, on terms scaled by theta.
*/
constexpr double kSim3SmallLogScale = 1e-3;

/*!
  Coefficients (A, B, C) of Strasdat's W matrix for rotation vector omega and log-scale sigma (see file comment).
  General case (with th = theta, s = sigma):
    A = (e^s (s sin th - th cos th) + th) / (th (s^2 + th^2)),
    B = (C - (e^s (s cos th + th sin th) - s) / (s^2 + th^2)) / th^2,
    C = (e^s - 1) / s.
  theta -> 0: A = ((s - 1) e^s + 1) / s^2, B = (e^s (s^2 - 2 s + 2) - 2) / (2 s^3).
  sigma -> 0: C = sum s^k / (k+1)!; with theta -> 0 too, A = sum s^k / (k! (k+2)), B = sum s^k / (2 k! (k+3)).
  At sigma = 0 the general A, B reduce to SO(3)'s (1 - cos)/th^2 and (th - sin)/th^3 (W = Jl(omega)).
*/
template <typename Scalar>
void sim3WCoefficients(const Eigen::Matrix<Scalar, 3, 1> &omega, const Scalar &sigma, Scalar &A, Scalar &B, Scalar &C)
{
  using std::abs;
  using std::cos;
  using std::exp;
  using std::expm1;
  using std::sin;
  using std::sqrt;
  const Scalar thetaSq = omega.squaredNorm();
  const bool smallSigma = abs(sigma) < Scalar(kSim3SmallLogScale);
  const Scalar sigma2 = sigma * sigma;
  const Scalar sigma3 = sigma2 * sigma;
  const Scalar sigma4 = sigma2 * sigma2;
  if (smallSigma) {
    C = Scalar(1) + sigma / Scalar(2) + sigma2 / Scalar(6) + sigma3 / Scalar(24) + sigma4 / Scalar(120);
  } else {
    C = expm1(sigma) / sigma;
  }
  if (thetaSq < Scalar(kSim3SmallAngleSq)) {
    if (smallSigma) {
      A = Scalar(0.5) + sigma / Scalar(3) + sigma2 / Scalar(8) + sigma3 / Scalar(30) + sigma4 / Scalar(144);
      B = Scalar(1) / Scalar(6) + sigma / Scalar(8) + sigma2 / Scalar(20) + sigma3 / Scalar(72) + sigma4 / Scalar(336);
    } else {
      const Scalar es = exp(sigma);
      A = ((sigma - Scalar(1)) * es + Scalar(1)) / sigma2;
      B = (es * (sigma2 - Scalar(2) * sigma + Scalar(2)) - Scalar(2)) / (Scalar(2) * sigma3);
    }
  } else {
    const Scalar theta = sqrt(thetaSq);
    const Scalar s = sin(theta);
    const Scalar c = cos(theta);
    const Scalar denom = sigma2 + thetaSq;
    // Both numerators are rewritten with E = e^s - 1 and 1 - cos t = 2 sin^2(t/2) so that no two terms of size
    // O(s) or O(t) cancel (the direct forms lose ~eps s / (s^2 + t^2), i.e. up to eps / t, for small s and t):
    //   e^s (s sin t - t cos t) + t  =  s sin t + 2 t sin^2(t/2) + E (s sin t - t cos t),
    //   e^s (s cos t + t sin t) - s  =  t sin t - 2 s sin^2(t/2) + E (s cos t + t sin t).
    const Scalar sinHalf = sin(Scalar(0.5) * theta);
    const Scalar twoSinHalfSq = Scalar(2) * sinHalf * sinHalf;
    const Scalar E = expm1(sigma);
    A = (sigma * s + theta * twoSinHalfSq + E * (sigma * s - theta * c)) / (theta * denom);
    const Scalar X = (theta * s - sigma * twoSinHalfSq + E * (sigma * c + theta * s)) / denom;
    B = (C - X) / thetaSq;
  }
}

//! Strasdat's W matrix: t = W upsilon in exp(upsilon, omega, sigma).
template <typename Scalar>
Eigen::Matrix<Scalar, 3, 3> sim3W(const Eigen::Matrix<Scalar, 3, 1> &omega, const Scalar &sigma)
{
  Scalar A, B, C;
  sim3WCoefficients<Scalar>(omega, sigma, A, B, C);
  const Eigen::Matrix<Scalar, 3, 3> Wx = so3Hat<Scalar>(omega);
  return A * Wx + B * (Wx * Wx) + C * Eigen::Matrix<Scalar, 3, 3>::Identity();
}

/*!
  Similarity aSb: p_a = s R p_b + t. Stored as unit quaternion, translation and scale (s > 0).
*/
template <typename Scalar> class Sim3
{
public:
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Mat4 = Eigen::Matrix<Scalar, 4, 4>;
  using Mat7 = Eigen::Matrix<Scalar, 7, 7>;
  using Tangent = Eigen::Matrix<Scalar, 7, 1>; //!< (upsilon, omega, sigma = log scale).
  using Quat = Eigen::Quaternion<Scalar>;

  //! Identity.
  Sim3() : m_q(Quat::Identity()), m_t(Vec3::Zero()), m_s(Scalar(1)) {}

  //! From a quaternion (normalised here), a translation and a scale; throws vpHSlamException unless s > 0.
  Sim3(const Quat &q, const Vec3 &t, const Scalar &s) : m_q(q), m_t(t), m_s(s)
  {
    if (!(s > Scalar(0))) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             std::string(__FILE__) + ":" + std::to_string(__LINE__) + ": Sim3 scale must be positive");
    }
    if (m_q.squaredNorm() < Scalar(kMinQuaternionSquaredNorm)) {
      throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                    ": Sim3 built from a zero quaternion");
    }
    m_q.normalize();
  }

  //! From a rotation matrix (assumed orthonormal), a translation and a scale.
  Sim3(const Mat3 &R, const Vec3 &t, const Scalar &s) : Sim3(Quat(R), t, s) {}

  //! From a rigid transform and a scale: [s R, t; 0, 1].
  Sim3(const SE3<Scalar> &T, const Scalar &s) : Sim3(T.unitQuaternion(), T.translation(), s) {}

  //! Exponential map (Strasdat): R = exp(omega), s = e^sigma, t = W(omega, sigma) upsilon.
  static Sim3 exp(const Tangent &xi)
  {
    using std::exp;
    const Vec3 upsilon = xi.template head<3>();
    const Vec3 omega = xi.template segment<3>(3);
    const Scalar sigma = xi(6);
    return Sim3(so3ExpQuaternion<Scalar>(omega), Vec3(sim3W<Scalar>(omega, sigma) * upsilon), exp(sigma));
  }

  //! Logarithm: the inverse of exp (rotation angle in [0, pi]); W is inverted in closed 3x3 form.
  Tangent log() const
  {
    using std::log;
    const Vec3 omega = so3LogQuaternion<Scalar>(m_q);
    const Scalar sigma = log(m_s);
    const Mat3 W = sim3W<Scalar>(omega, sigma);
    Tangent xi;
    xi.template head<3>() = W.inverse() * m_t;
    xi.template segment<3>(3) = omega;
    xi(6) = sigma;
    return xi;
  }

  //! 4x4 Lie-algebra matrix [[omega]x + sigma I, upsilon; 0, 0].
  static Mat4 hat(const Tangent &xi)
  {
    Mat4 X = Mat4::Zero();
    X.template topLeftCorner<3, 3>() = so3Hat<Scalar>(xi.template segment<3>(3)) + xi(6) * Mat3::Identity();
    X.template topRightCorner<3, 1>() = xi.template head<3>();
    return X;
  }

  //! Inverse of hat.
  static Tangent vee(const Mat4 &X)
  {
    Tangent xi;
    xi.template head<3>() = X.template topRightCorner<3, 1>();
    xi.template segment<3>(3) = so3Vee<Scalar>(X.template topLeftCorner<3, 3>());
    xi(6) = X.template topLeftCorner<3, 3>().trace() / Scalar(3);
    return xi;
  }

  //! Composition: (s1 R1, t1)(s2 R2, t2) = (s1 s2 R1 R2, s1 R1 t2 + t1).
  Sim3 operator*(const Sim3 &other) const
  {
    return Sim3(m_q * other.m_q, Vec3(m_s * (m_q * other.m_t) + m_t), m_s * other.m_s);
  }

  //! Action on a point: s R p + t.
  Vec3 operator*(const Vec3 &p) const { return m_s * (m_q * p) + m_t; }

  //! Inverse: (R^T / s, -R^T t / s).
  Sim3 inverse() const
  {
    const Quat qInv = m_q.conjugate();
    const Scalar sInv = Scalar(1) / m_s;
    return Sim3(qInv, Vec3(-sInv * (qInv * m_t)), sInv);
  }

  /*!
    Adjoint (7x7), S exp(xi) S^-1 = exp(Ad_S xi). From S hat(xi) S^-1 with (upsilon, omega, sigma) ordering:
    upsilon' = s R upsilon + [t]x R omega - sigma t, omega' = R omega, sigma' = sigma.
  */
  Mat7 adjoint() const
  {
    const Mat3 R = rotationMatrix();
    Mat7 Ad = Mat7::Zero();
    Ad.template block<3, 3>(0, 0) = m_s * R;
    Ad.template block<3, 3>(0, 3) = so3Hat<Scalar>(m_t) * R;
    Ad.template block<3, 1>(0, 6) = -m_t;
    Ad.template block<3, 3>(3, 3) = R;
    Ad(6, 6) = Scalar(1);
    return Ad;
  }

  /*!
    Adjoint of the Lie algebra (7x7), ad_xi eta = vee([hat(xi), hat(eta)]), the first-order term of exp(xi)'s
    adjoint (Ad_exp(xi) = I + ad_xi + ...). In (upsilon, omega, sigma) order:
    [[omega]x + sigma I, [upsilon]x, -upsilon; 0, [omega]x, 0; 0, 0, 0].
  */
  static Mat7 ad(const Tangent &xi)
  {
    const Vec3 upsilon = xi.template head<3>();
    const Mat3 omegaHat = so3Hat<Scalar>(Vec3(xi.template segment<3>(3)));
    Mat7 a = Mat7::Zero();
    a.template block<3, 3>(0, 0) = omegaHat + xi(6) * Mat3::Identity();
    a.template block<3, 3>(0, 3) = so3Hat<Scalar>(upsilon);
    a.template block<3, 1>(0, 6) = -upsilon;
    a.template block<3, 3>(3, 3) = omegaHat;
    return a;
  }

  //! 4x4 matrix [s R, t; 0, 1].
  Mat4 matrix() const
  {
    Mat4 M = Mat4::Identity();
    M.template topLeftCorner<3, 3>() = m_s * rotationMatrix();
    M.template topRightCorner<3, 1>() = m_t;
    return M;
  }

  /*!
    d(exp(xi) * S * p) / d xi at xi = 0 (left perturbation): [I, -[S p]x, S p], the pose block of a Sim(3)
    reprojection or 3D-3D residual.
  */
  Eigen::Matrix<Scalar, 3, 7> jacobianActionLeftPerturbation(const Vec3 &p) const
  {
    const Vec3 q = *this * p;
    Eigen::Matrix<Scalar, 3, 7> J;
    J.template leftCols<3>().setIdentity();
    J.template block<3, 3>(0, 3) = -so3Hat<Scalar>(q);
    J.template rightCols<1>() = q;
    return J;
  }

  //! d(S * p) / dp = s R.
  Mat3 jacobianActionPoint() const { return m_s * rotationMatrix(); }

  //! The rigid part (R, t), dropping the scale.
  SE3<Scalar> rigid() const { return SE3<Scalar>(m_q, m_t); }

  Mat3 rotationMatrix() const { return m_q.toRotationMatrix(); }
  const Quat &unitQuaternion() const { return m_q; }
  const Vec3 &translation() const { return m_t; }
  const Scalar &scale() const { return m_s; }

  template <typename Other> Sim3<Other> cast() const
  {
    return Sim3<Other>(m_q.template cast<Other>(), m_t.template cast<Other>(), Other(m_s));
  }

private:
  Quat m_q;   //!< Unit quaternion of the rotation.
  Vec3 m_t;   //!< Translation.
  Scalar m_s; //!< Scale s > 0 (dimensionless).
};

using Sim3d = Sim3<double>;

} // namespace hslam

#endif
