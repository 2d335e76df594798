/*
 * H-SLAM for ViSP.
 */
/*!
  \file SE3.h
  \brief Rigid-body transform SE(3) on Eigen, templated on the scalar type (double, ceres::Jet), no allocation.

  Twist ordering: a tangent vector xi is the 6-vector (upsilon, omega) = (translation part, rotation part), the
  same order as ViSP's velocity twists (vpExponentialMap) and Sophus. Every 6x6 matrix below (Adjoint,
  Jacobians) uses that order for its rows and columns.

  Perturbation conventions: "left" means exp(xi) * T, "right" means T * exp(xi). Jacobians follow Barfoot,
  "State Estimation for Robotics" (2017), sec. 7.1 (whose xi = (rho, phi) is also translation first).
*/
#ifndef HSLAM_MATH_SE3_H
#define HSLAM_MATH_SE3_H

#include "math/SO3.h"

#include <visp3/hslam/vpHSlamException.h>

#include <string>

namespace hslam
{
/*!
  Below this squared rotation angle (rad^2) the coefficients of the Q block of the SE(3) Jacobian are taken from
  their Taylor series (to the theta^4 term). The closed form of the last coefficient,
  (2 t - 3 sin t + t cos t) / (2 t^5), cancels five orders: at t = 1e-2 it still keeps ~1e-6 relative accuracy
  (eps * 60 / t^4) on a term scaled by t^3, while the first dropped Taylor term is t^6 / 1.2e7 ~ 1e-19.
*/
constexpr double kSE3JacobianSmallAngleSq = 1e-4;
//! Quaternions whose squared norm is below this cannot be normalised into a rotation.
constexpr double kMinQuaternionSquaredNorm = 1e-20;

/*!
  Rigid transform aMb: maps a point expressed in frame b to frame a, p_a = R p_b + t.
  Stored as a unit quaternion (renormalised on construction) and a translation.
*/
template <typename Scalar> class SE3
{
public:
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Mat4 = Eigen::Matrix<Scalar, 4, 4>;
  using Mat6 = Eigen::Matrix<Scalar, 6, 6>;
  using Tangent = Eigen::Matrix<Scalar, 6, 1>; //!< (upsilon, omega): translation part first.
  using Quat = Eigen::Quaternion<Scalar>;

  //! Identity.
  SE3() : m_q(Quat::Identity()), m_t(Vec3::Zero()) {}

  //! From a quaternion (normalised here; throws vpHSlamException if it is ~0) and a translation.
  SE3(const Quat &q, const Vec3 &t) : m_q(q), m_t(t)
  {
    if (m_q.squaredNorm() < Scalar(kMinQuaternionSquaredNorm)) {
      throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                    ": SE3 built from a zero quaternion");
    }
    m_q.normalize();
  }

  /*!
    From a quaternion the caller knows to be unit (read back from a file that stored a unit one): kept bit for bit,
    so that a pose written and read again is the same pose. Anything else goes through the normalising constructor.
  */
  static SE3 fromUnitQuaternion(const Quat &q, const Vec3 &t)
  {
    SE3 T;
    T.m_q = q;
    T.m_t = t;
    return T;
  }

  //! From a rotation matrix (assumed orthonormal, see ViSPConversions.h to repair one) and a translation.
  SE3(const Mat3 &R, const Vec3 &t) : SE3(Quat(R), t) {}

  /*!
    Exponential map: R = exp(omega), t = Jl(omega) upsilon, where Jl is the left Jacobian of SO(3) (the "V"
    matrix of SE(3)).
  */
  static SE3 exp(const Tangent &xi)
  {
    const Vec3 upsilon = xi.template head<3>();
    const Vec3 omega = xi.template tail<3>();
    return SE3(so3ExpQuaternion<Scalar>(omega), so3LeftJacobian<Scalar>(omega) * upsilon);
  }

  //! Logarithm: the inverse of exp, rotation angle in [0, pi].
  Tangent log() const
  {
    const Vec3 omega = so3LogQuaternion<Scalar>(m_q);
    Tangent xi;
    xi.template head<3>() = so3LeftJacobianInverse<Scalar>(omega) * m_t;
    xi.template tail<3>() = omega;
    return xi;
  }

  //! 4x4 matrix of a twist in the Lie algebra: [[omega]x, upsilon; 0, 0].
  static Mat4 hat(const Tangent &xi)
  {
    Mat4 X = Mat4::Zero();
    X.template topLeftCorner<3, 3>() = so3Hat<Scalar>(xi.template tail<3>());
    X.template topRightCorner<3, 1>() = xi.template head<3>();
    return X;
  }

  //! Inverse of hat.
  static Tangent vee(const Mat4 &X)
  {
    Tangent xi;
    xi.template head<3>() = X.template topRightCorner<3, 1>();
    xi.template tail<3>() = so3Vee<Scalar>(X.template topLeftCorner<3, 3>());
    return xi;
  }

  //! Composition aMc = aMb * bMc.
  SE3 operator*(const SE3 &other) const { return SE3(m_q * other.m_q, m_t + m_q * other.m_t); }

  //! Action on a point: R p + t.
  Vec3 operator*(const Vec3 &p) const { return m_q * p + m_t; }

  //! Inverse bMa of aMb.
  SE3 inverse() const
  {
    const Quat qInv = m_q.conjugate();
    return SE3(qInv, -(qInv * m_t));
  }

  /*!
    Adjoint Ad_T (6x6), such that T exp(xi) T^-1 = exp(Ad_T xi). With (upsilon, omega) ordering:
    Ad_T = [R, [t]x R; 0, R].
  */
  Mat6 adjoint() const
  {
    const Mat3 R = rotationMatrix();
    Mat6 Ad;
    Ad.template topLeftCorner<3, 3>() = R;
    Ad.template topRightCorner<3, 3>() = so3Hat<Scalar>(m_t) * R;
    Ad.template bottomLeftCorner<3, 3>().setZero();
    Ad.template bottomRightCorner<3, 3>() = R;
    return Ad;
  }

  //! Homogeneous 4x4 matrix [R, t; 0, 1].
  Mat4 matrix() const
  {
    Mat4 M = Mat4::Identity();
    M.template topLeftCorner<3, 3>() = rotationMatrix();
    M.template topRightCorner<3, 1>() = m_t;
    return M;
  }

  Mat3 rotationMatrix() const { return m_q.toRotationMatrix(); }
  const Quat &unitQuaternion() const { return m_q; }
  const Vec3 &translation() const { return m_t; }
  Vec3 &translation() { return m_t; }

  //! The same transform with another scalar type (e.g. double -> ceres::Jet for constants in a cost functor).
  template <typename Other> SE3<Other> cast() const
  {
    return SE3<Other>(m_q.template cast<Other>(), m_t.template cast<Other>());
  }

  /*!
    d(exp(xi) * T * p) / d xi at xi = 0 (left perturbation of the transform applied to p): [I, -[T p]x].
    This is the pose block of a reprojection Jacobian when poses are updated as T <- exp(delta) T.
  */
  Eigen::Matrix<Scalar, 3, 6> jacobianActionLeftPerturbation(const Vec3 &p) const
  {
    Eigen::Matrix<Scalar, 3, 6> J;
    J.template leftCols<3>().setIdentity();
    J.template rightCols<3>() = -so3Hat<Scalar>(Vec3(*this * p));
    return J;
  }

  //! d(T * exp(xi) * p) / d xi at xi = 0 (right perturbation): R [I, -[p]x].
  Eigen::Matrix<Scalar, 3, 6> jacobianActionRightPerturbation(const Vec3 &p) const
  {
    const Mat3 R = rotationMatrix();
    Eigen::Matrix<Scalar, 3, 6> J;
    J.template leftCols<3>() = R;
    J.template rightCols<3>() = -R * so3Hat<Scalar>(p);
    return J;
  }

  //! d(T * p) / dp = R.
  Mat3 jacobianActionPoint() const { return rotationMatrix(); }

  /*!
    Left Jacobian of SE(3) (Barfoot 2017, sec. 7.1): J = [Jl(omega), Q(upsilon, omega); 0, Jl(omega)], so that
    exp(xi + d) ~= exp(J d) exp(xi).
  */
  static Mat6 leftJacobian(const Tangent &xi)
  {
    const Vec3 omega = xi.template tail<3>();
    const Mat3 Jl = so3LeftJacobian<Scalar>(omega);
    Mat6 J;
    J.template topLeftCorner<3, 3>() = Jl;
    J.template topRightCorner<3, 3>() = jacobianQ(xi);
    J.template bottomLeftCorner<3, 3>().setZero();
    J.template bottomRightCorner<3, 3>() = Jl;
    return J;
  }

  //! Inverse of the left Jacobian: [Jl^-1, -Jl^-1 Q Jl^-1; 0, Jl^-1] (block triangular, closed form).
  static Mat6 leftJacobianInverse(const Tangent &xi)
  {
    const Vec3 omega = xi.template tail<3>();
    const Mat3 JlInv = so3LeftJacobianInverse<Scalar>(omega);
    Mat6 J;
    J.template topLeftCorner<3, 3>() = JlInv;
    J.template topRightCorner<3, 3>() = -JlInv * jacobianQ(xi) * JlInv;
    J.template bottomLeftCorner<3, 3>().setZero();
    J.template bottomRightCorner<3, 3>() = JlInv;
    return J;
  }

  //! Right Jacobian of SE(3): Jr(xi) = Jl(-xi); exp(xi + d) ~= exp(xi) exp(Jr d).
  static Mat6 rightJacobian(const Tangent &xi) { return leftJacobian(Tangent(-xi)); }

  //! Inverse of the right Jacobian: Jr^-1(xi) = Jl^-1(-xi).
  static Mat6 rightJacobianInverse(const Tangent &xi) { return leftJacobianInverse(Tangent(-xi)); }

  /*!
    d log(T exp(delta)) / d delta at delta = 0, i.e. Jr^-1(log T). This is the Jacobian of a pose-graph residual
    r = log(Z^-1 Ti^-1 Tj) with respect to a right-multiplied update Tj <- Tj exp(delta). For Ti <- Ti exp(delta),
    Z^-1 exp(-delta) Ti^-1 Tj = E exp(-Ad_{Tj^-1 Ti} delta) with E = Z^-1 Ti^-1 Tj, so dr/d delta_i =
    -Jr^-1(r) Ad_{Tj^-1 Ti}.
  */
  Mat6 jacobianLogRightPerturbation() const { return rightJacobianInverse(log()); }

  //! d log(exp(delta) T) / d delta at delta = 0, i.e. Jl^-1(log T).
  Mat6 jacobianLogLeftPerturbation() const { return leftJacobianInverse(log()); }

private:
  /*!
    Q(upsilon, omega) block of the SE(3) left Jacobian (Barfoot 2017, sec. 7.1), with P = [upsilon]x, W = [omega]x:
    Q = 1/2 P + c1 (W P + P W + W P W) + c2 (W W P + P W W - 3 W P W) + c3 (W P W W + W W P W),
    c1 = (t - sin t)/t^3, c2 = (t^2 + 2 cos t - 2)/(2 t^4), c3 = (2 t - 3 sin t + t cos t)/(2 t^5).
    Taylor: c1 ~ 1/6 - t^2/120 + t^4/5040, c2 ~ 1/24 - t^2/720 + t^4/40320, c3 ~ 1/120 - t^2/2520 + t^4/120960.
  */
  static Mat3 jacobianQ(const Tangent &xi)
  {
    using std::cos;
    using std::sin;
    using std::sqrt;
    const Mat3 P = so3Hat<Scalar>(xi.template head<3>());
    const Mat3 W = so3Hat<Scalar>(xi.template tail<3>());
    const Scalar thetaSq = xi.template tail<3>().squaredNorm();
    Scalar c1, c2, c3;
    if (thetaSq < Scalar(kSE3JacobianSmallAngleSq)) {
      const Scalar theta4 = thetaSq * thetaSq;
      c1 = Scalar(1) / Scalar(6) - thetaSq / Scalar(120) + theta4 / Scalar(5040);
      c2 = Scalar(1) / Scalar(24) - thetaSq / Scalar(720) + theta4 / Scalar(40320);
      c3 = Scalar(1) / Scalar(120) - thetaSq / Scalar(2520) + theta4 / Scalar(120960);
    } else {
      const Scalar theta = sqrt(thetaSq);
      const Scalar s = sin(theta);
      const Scalar c = cos(theta);
      const Scalar theta4 = thetaSq * thetaSq;
      c1 = (theta - s) / (thetaSq * theta);
      // t^2 + 2 cos t - 2 = (t - 2 sin(t/2)) (t + 2 sin(t/2)): the factored form cancels two orders less.
      const Scalar twoSinHalf = Scalar(2) * sin(Scalar(0.5) * theta);
      c2 = (theta - twoSinHalf) * (theta + twoSinHalf) / (Scalar(2) * theta4);
      c3 = (Scalar(2) * theta - Scalar(3) * s + theta * c) / (Scalar(2) * theta4 * theta);
    }
    const Mat3 WP = W * P;
    const Mat3 PW = P * W;
    const Mat3 WPW = WP * W;
    return Scalar(0.5) * P + c1 * (WP + PW + WPW) + c2 * (W * WP + PW * W - Scalar(3) * WPW) + c3 * (WPW * W + W * WPW);
  }

  Quat m_q; //!< Unit quaternion of the rotation.
  Vec3 m_t; //!< Translation (same unit as the points it acts on, metres in H-SLAM).
};

using SE3d = SE3<double>;

} // namespace hslam

#endif
