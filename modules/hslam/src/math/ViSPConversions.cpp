/*
 * H-SLAM for ViSP.
 */
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <cmath>
#include <string>

namespace hslam
{
namespace
{
std::string where(int line)
{
  return std::string(__FILE__) + ":" + std::to_string(line) + ": ";
}

//! Checks a homogeneous matrix whose rotation block may have drifted; returns the repaired rotation.
Eigen::Matrix3d checkedRotation(const vpHomogeneousMatrix &aMb, int line)
{
  const Eigen::Matrix4d M = toEigen(aMb);
  if (!M.allFinite()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(line) + "homogeneous matrix is not finite");
  }
  const Eigen::RowVector4d lastRow(0.0, 0.0, 0.0, 1.0);
  if ((M.row(3) - lastRow).cwiseAbs().maxCoeff() > kMaxHomogeneousRowDrift) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(line) + "homogeneous matrix last row is not (0, 0, 0, 1)");
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  const double drift = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (drift > kMaxRotationDrift || !(R.determinant() > 0.0)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(line) + "rotation block is not a rotation (max |R^T R - I| = " +
                               std::to_string(drift) + ", det = " + std::to_string(R.determinant()) + ")");
  }
  return nearestRotation(R);
}
} // namespace

Eigen::Matrix3d toEigen(const vpRotationMatrix &R)
{
  Eigen::Matrix3d out;
  for (unsigned int i = 0; i < 3; ++i) {
    for (unsigned int j = 0; j < 3; ++j) {
      out(i, j) = R[i][j];
    }
  }
  return out;
}

Eigen::Matrix4d toEigen(const vpHomogeneousMatrix &M)
{
  Eigen::Matrix4d out;
  for (unsigned int i = 0; i < 4; ++i) {
    for (unsigned int j = 0; j < 4; ++j) {
      out(i, j) = M[i][j];
    }
  }
  return out;
}

Eigen::Vector3d toEigen(const vpTranslationVector &t)
{
  return Eigen::Vector3d(t[0], t[1], t[2]);
}

Eigen::Vector3d toEigen(const vpThetaUVector &tu)
{
  return Eigen::Vector3d(tu[0], tu[1], tu[2]);
}

vpRotationMatrix toVpRotationMatrix(const Eigen::Matrix3d &R)
{
  vpRotationMatrix out;
  for (unsigned int i = 0; i < 3; ++i) {
    for (unsigned int j = 0; j < 3; ++j) {
      out[i][j] = R(i, j);
    }
  }
  return out;
}

vpHomogeneousMatrix toVpHomogeneousMatrix(const Eigen::Matrix4d &M)
{
  vpHomogeneousMatrix out;
  for (unsigned int i = 0; i < 4; ++i) {
    for (unsigned int j = 0; j < 4; ++j) {
      out[i][j] = M(i, j);
    }
  }
  return out;
}

vpTranslationVector toVpTranslationVector(const Eigen::Vector3d &t)
{
  return vpTranslationVector(t(0), t(1), t(2));
}

Eigen::Matrix3d nearestRotation(const Eigen::Matrix3d &M)
{
  if (!M.allFinite()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(__LINE__) + "matrix is not finite");
  }
  // Polar decomposition (Higham 1986): the orthogonal factor U V^T is the nearest orthogonal matrix; flipping
  // the last singular direction when det < 0 gives the nearest proper rotation.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d V = svd.matrixV();
  Eigen::Vector3d d(1.0, 1.0, (U * V.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  return U * d.asDiagonal() * V.transpose();
}

vpHomogeneousMatrix orthonormalize(const vpHomogeneousMatrix &aMb)
{
  const Eigen::Matrix3d R = checkedRotation(aMb, __LINE__);
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = R;
  M.topRightCorner<3, 1>() = toEigen(aMb).topRightCorner<3, 1>();
  return toVpHomogeneousMatrix(M);
}

SE3d toSE3(const vpHomogeneousMatrix &aMb)
{
  const Eigen::Matrix3d R = checkedRotation(aMb, __LINE__);
  return SE3d(R, Eigen::Vector3d(aMb[0][3], aMb[1][3], aMb[2][3]));
}

vpHomogeneousMatrix toVpHomogeneousMatrix(const SE3d &aMb)
{
  return toVpHomogeneousMatrix(aMb.matrix());
}

Sim3d toSim3(const vpHomogeneousMatrix &aMb, double scale)
{
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(__LINE__) + "Sim3 scale must be positive and finite, got " + std::to_string(scale));
  }
  return Sim3d(toSE3(aMb), scale);
}

vpHomogeneousMatrix toVpHomogeneousMatrix(const Sim3d &aSb, double &scale)
{
  scale = aSb.scale();
  return toVpHomogeneousMatrix(aSb.rigid());
}

} // namespace hslam
