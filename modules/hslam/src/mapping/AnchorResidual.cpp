/*
 * H-SLAM for ViSP.
 */
#include "mapping/AnchorResidual.h"

#include <cmath>
#include <limits>

namespace hslam
{
namespace
{
//! Depth in the stored camera below which the anchor is not evaluated (behind or at the camera centre).
constexpr double kMinAnchorDepth = 1e-6;
} // namespace

double evaluateAnchor(const PinholeIntrinsics &K, const SE3d &hostMw, double u, double v, double idepth,
                      const PointAnchor &anchor, AnchorLinearization *lin)
{
  if (!anchor.active || !(idepth > 0.)) {
    return 0.;
  }
  const SE3d aMh = anchor.anchorMw * hostMw.inverse();
  const Eigen::Vector3d Ph = K.unproject(u, v, idepth);
  const Eigen::Vector3d Pa = aMh * Ph;
  if (!(Pa.z() > kMinAnchorDepth)) {
    return 0.;
  }
  const double iz = 1. / Pa.z();
  const Eigen::Vector2d rPx(K.fx * Pa.x() * iz + K.cx - anchor.u, K.fy * Pa.y() * iz + K.cy - anchor.v);
  const double rRho = iz - anchor.idepth;
  const double norm = rPx.norm();
  const double k = anchor.huberPx;
  const double huber = norm <= k ? norm * norm : k * (2. * norm - k);
  const double energy = anchor.pixelWeight * huber + anchor.idepthWeight * rRho * rRho;
  if (lin) {
    // d(u', v', 1/Z) / dP_a.
    Eigen::Matrix3d Jproj;
    Jproj << K.fx * iz, 0., -K.fx * Pa.x() * iz * iz, 0., K.fy * iz, -K.fy * Pa.y() * iz * iz, 0., 0., -iz * iz;
    Eigen::Matrix<double, 3, 7> JP;
    JP.leftCols<6>() = -aMh.jacobianActionRightPerturbation(Ph);
    JP.col(6) = -aMh.rotationMatrix() * Ph / idepth;
    const Eigen::Matrix<double, 3, 7> J = Jproj * JP;
    const double wPx = anchor.pixelWeight * (norm <= k ? 1. : k / norm);
    const Eigen::Vector3d w(wPx, wPx, anchor.idepthWeight);
    const Eigen::Vector3d r(rPx.x(), rPx.y(), rRho);
    const Eigen::Matrix<double, 7, 3> JtW = J.transpose() * w.asDiagonal();
    const Eigen::Matrix<double, 7, 7> H = JtW * J;
    const Eigen::Matrix<double, 7, 1> b = JtW * r;
    lin->Hxx = H.topLeftCorner<6, 6>();
    lin->bx = b.head<6>();
    lin->Hxr = H.block<6, 1>(0, 6);
    lin->Hrr = H(6, 6);
    lin->br = b[6];
  }
  return energy;
}

double anchorPixelError(const PinholeIntrinsics &K, const SE3d &hostMw, double u, double v, double idepth,
                        const SE3d &anchorMw, double anchorU, double anchorV)
{
  const Eigen::Vector3d Pa = anchorMw * (hostMw.inverse() * K.unproject(u, v, idepth));
  if (!(idepth > 0.) || !(Pa.z() > kMinAnchorDepth)) {
    return std::numeric_limits<double>::infinity();
  }
  return std::hypot(K.fx * Pa.x() / Pa.z() + K.cx - anchorU, K.fy * Pa.y() / Pa.z() + K.cy - anchorV);
}
} // namespace hslam
