/*
 * H-SLAM for ViSP.
 */
/*!
  \file Sim3Parameters.h
  \brief A Sim(3) element as 8 Ceres parameters and its manifold (private to loop/: Sim3Solver, PoseGraph).

  Storage: [qx, qy, qz, qw, tx, ty, tz, sigma] (Eigen quaternion order, translation, log-scale). The manifold has 7
  degrees of freedom, updated on the left: Plus(x, d) = exp(d) * S(x), Minus(y, x) = log(S(y) * S(x)^-1), with the
  tangent order of Sim3.h (upsilon, omega, sigma). Ceres differentiates both through Sim3<Jet>.
*/
#ifndef HSLAM_LOOP_SIM3_PARAMETERS_H
#define HSLAM_LOOP_SIM3_PARAMETERS_H

#include "math/Sim3.h"

#include <ceres/autodiff_manifold.h>

#include <array>
#include <cmath>

namespace hslam
{
constexpr int kSim3ParameterSize = 8;
constexpr int kSim3TangentSize = 7;

template <typename T> Sim3<T> sim3FromParameters(const T *x)
{
  using std::exp;
  const Eigen::Quaternion<T> q(x[3], x[0], x[1], x[2]);
  return Sim3<T>(q, Eigen::Matrix<T, 3, 1>(x[4], x[5], x[6]), exp(x[7]));
}

template <typename T> void sim3ToParameters(const Sim3<T> &S, T *x)
{
  using std::log;
  const Eigen::Quaternion<T> &q = S.unitQuaternion();
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  x[4] = S.translation()[0];
  x[5] = S.translation()[1];
  x[6] = S.translation()[2];
  x[7] = log(S.scale());
}

inline std::array<double, kSim3ParameterSize> sim3Parameters(const Sim3<double> &S)
{
  std::array<double, kSim3ParameterSize> x;
  sim3ToParameters(S, x.data());
  return x;
}

//! Left-multiplicative update on Sim(3) (see file comment).
struct Sim3LeftPlus {
  template <typename T> bool Plus(const T *x, const T *delta, T *out) const
  {
    const Eigen::Map<const Eigen::Matrix<T, 7, 1>> d(delta);
    sim3ToParameters(Sim3<T>::exp(typename Sim3<T>::Tangent(d)) * sim3FromParameters(x), out);
    return true;
  }
  template <typename T> bool Minus(const T *y, const T *x, T *out) const
  {
    Eigen::Map<Eigen::Matrix<T, 7, 1>> result(out);
    result = (sim3FromParameters(y) * sim3FromParameters(x).inverse()).log();
    return true;
  }
};

inline ceres::Manifold *newSim3Manifold()
{
  return new ceres::AutoDiffManifold<Sim3LeftPlus, kSim3ParameterSize, kSim3TangentSize>();
}
} // namespace hslam

#endif
