/*
 * H-SLAM for ViSP.
 */
/*!
  \file ViSPConversions.h
  \brief Conversions between the internal Eigen maths (SE3, Sim3, matrices) and ViSP's geometry types.

  The public API speaks vpHomogeneousMatrix; the estimator works on hslam::SE3d / Sim3d. These functions are the
  only bridge, so the frame convention is kept: toSE3(aMb) is the transform that maps points of frame b to frame a,
  exactly as aMb does. All functions are thread-safe (no state) and exported for the tests.

  ViSP matrices read from text (trajectories, calibration files, printed poses) carry a rotation that is only
  orthonormal to the printed precision; toSE3, toSim3 and orthonormalize project it onto SO(3) (the nearest
  rotation in Frobenius norm) and reject matrices too far from a rotation to be one.
*/
#ifndef HSLAM_MATH_VISP_CONVERSIONS_H
#define HSLAM_MATH_VISP_CONVERSIONS_H

#include "math/SE3.h"
#include "math/Sim3.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpRotationMatrix.h>
#include <visp3/core/vpThetaUVector.h>
#include <visp3/core/vpTranslationVector.h>

namespace hslam
{
/*!
  Largest |(R^T R - I)_ij| accepted as rounding drift of a rotation block. A rotation printed with 4 significant
  digits drifts by ~1e-4; anything beyond 1e-3 is not a rotation that lost digits but a wrong matrix (a scaled or
  sheared one, or the wrong block of a file), and is rejected rather than silently projected.
*/
constexpr double kMaxRotationDrift = 1e-3;
//! Largest deviation accepted in the last row of a homogeneous matrix, (0, 0, 0, 1).
constexpr double kMaxHomogeneousRowDrift = 1e-9;

VISP_EXPORT Eigen::Matrix3d toEigen(const vpRotationMatrix &R);
VISP_EXPORT Eigen::Matrix4d toEigen(const vpHomogeneousMatrix &M);
VISP_EXPORT Eigen::Vector3d toEigen(const vpTranslationVector &t);
//! The rotation vector (theta u) as an Eigen vector; same convention as so3Log.
VISP_EXPORT Eigen::Vector3d toEigen(const vpThetaUVector &tu);

//! Copies the 3x3 matrix as is (no check: use nearestRotation first if it may have drifted).
VISP_EXPORT vpRotationMatrix toVpRotationMatrix(const Eigen::Matrix3d &R);
//! Copies the 4x4 matrix as is.
VISP_EXPORT vpHomogeneousMatrix toVpHomogeneousMatrix(const Eigen::Matrix4d &M);
VISP_EXPORT vpTranslationVector toVpTranslationVector(const Eigen::Vector3d &t);

/*!
  Nearest rotation to M in Frobenius norm (polar decomposition by SVD: U diag(1, 1, det(U V^T)) V^T).
  Throws vpHSlamException(invalidArgument) if M is not finite.
*/
VISP_EXPORT Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d &M);

/*!
  aMb with its rotation block replaced by the nearest rotation. Throws vpHSlamException(invalidArgument) when
  the rotation drifted by more than kMaxRotationDrift, its determinant is not positive, the last row is not
  (0, 0, 0, 1) or an entry is not finite.
*/
VISP_EXPORT vpHomogeneousMatrix orthonormalize(const vpHomogeneousMatrix &aMb);

//! SE3 equal to aMb (same frames); the rotation is re-orthonormalised and checked as in orthonormalize().
VISP_EXPORT SE3d toSE3(const vpHomogeneousMatrix &aMb);
VISP_EXPORT vpHomogeneousMatrix toVpHomogeneousMatrix(const SE3d &aMb);

/*!
  Sim3 mapping p_b to scale * R p_b + t, from a rigid aMb = (R, t) and a positive scale. The rotation is
  re-orthonormalised as in orthonormalize(); throws vpHSlamException(invalidArgument) unless scale > 0.
*/
VISP_EXPORT Sim3d toSim3(const vpHomogeneousMatrix &aMb, double scale);
//! Splits aSb into its rigid part (R, t) returned as a vpHomogeneousMatrix and its scale.
VISP_EXPORT vpHomogeneousMatrix toVpHomogeneousMatrix(const Sim3d &aSb, double &scale);

} // namespace hslam

#endif
