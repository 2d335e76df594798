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

//! |log-scale| above this is no similarity a map can have (scale beyond e^+-20): evaluation is refused.
constexpr double kMaxAbsLogScale = 20.;

//! True when all n entries are finite; functors refuse to evaluate otherwise.
template <typename T> bool allFinite(const T *x, int n)
{
  using std::isfinite;
  for (int i = 0; i < n; ++i) {
    if (!isfinite(x[i])) {
      return false;
    }
  }
  return true;
}

/*!
  Finite parameters with a usable scale (Sim3's constructor would throw on a scale that underflows to 0). The bounds
  are included: Sim3LeftPlus saturates a step onto them, and a parameter block Ceres cannot evaluate its manifold at
  is a fatal CHECK in Ceres (a 650-keyframe run of hslam_many_laps aborted on one).
*/
template <typename T> bool sim3ParametersValid(const T *x)
{
  return allFinite(x, kSim3ParameterSize) && x[7] <= T(kMaxAbsLogScale) && x[7] >= T(-kMaxAbsLogScale);
}

//! Left-multiplicative update on Sim(3) (see file comment).
struct Sim3LeftPlus {
  template <typename T> bool Plus(const T *x, const T *delta, T *out) const
  {
    if (!sim3ParametersValid(x) || !allFinite(delta, kSim3TangentSize)) {
      return false;
    }
    // The log-scale step saturates (Ceres also adds the raw gradient for its convergence test): a scale that
    // over- or underflows would not be a similarity.
    typename Sim3<T>::Tangent d(Eigen::Map<const Eigen::Matrix<T, 7, 1>>(delta).eval());
    const T logScale = d(6) + x[7];
    if (logScale > T(kMaxAbsLogScale)) {
      d(6) = T(kMaxAbsLogScale) - x[7];
    } else if (logScale < T(-kMaxAbsLogScale)) {
      d(6) = T(-kMaxAbsLogScale) - x[7];
    }
    sim3ToParameters(Sim3<T>::exp(d) * sim3FromParameters(x), out);
    // exp(d) * S rounds: a step saturated onto a bound can land a last digit beyond it, where the next evaluation
    // would be refused (Ceres then logs a warning per refused Jacobian, and CHECK-fails at a block's start).
    if (out[7] > T(kMaxAbsLogScale)) {
      out[7] = T(kMaxAbsLogScale);
    } else if (out[7] < T(-kMaxAbsLogScale)) {
      out[7] = T(-kMaxAbsLogScale);
    }
    return true;
  }
  template <typename T> bool Minus(const T *y, const T *x, T *out) const
  {
    if (!sim3ParametersValid(x) || !sim3ParametersValid(y)) {
      return false;
    }
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
