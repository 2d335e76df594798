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

//! The window point (host pixel, inverse depth, host pose) in the stored camera: aMh, P_h, P_a and the pixel
//! residual against (anchorU, anchorV). False when the inverse depth is not positive or P_a is not in front.
bool projectIntoStored(const PinholeIntrinsics &K, const SE3d &hostMw, double u, double v, double idepth,
                       const SE3d &anchorMw, double anchorU, double anchorV, SE3d &aMh, Eigen::Vector3d &Ph,
                       Eigen::Vector3d &Pa, Eigen::Vector2d &rPx)
{
  if (!(idepth > 0.)) {
    return false;
  }
  aMh = anchorMw * hostMw.inverse();
  Ph = K.unproject(u, v, idepth);
  Pa = aMh * Ph;
  if (!(Pa.z() > kMinAnchorDepth)) {
    return false;
  }
  const double iz = 1. / Pa.z();
  rPx = Eigen::Vector2d(K.fx * Pa.x() * iz + K.cx - anchorU, K.fy * Pa.y() * iz + K.cy - anchorV);
  return true;
}
} // namespace

double evaluateAnchor(const PinholeIntrinsics &K, const SE3d &hostMw, double u, double v, double idepth,
                      const PointAnchor &anchor, AnchorLinearization *lin)
{
  SE3d aMh;
  Eigen::Vector3d Ph, Pa;
  Eigen::Vector2d rPx;
  if (!anchor.active ||
      !projectIntoStored(K, hostMw, u, v, idepth, anchor.anchorMw, anchor.u, anchor.v, aMh, Ph, Pa, rPx)) {
    return 0.;
  }
  const double iz = 1. / Pa.z();
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
  SE3d aMh;
  Eigen::Vector3d Ph, Pa;
  Eigen::Vector2d rPx;
  if (!projectIntoStored(K, hostMw, u, v, idepth, anchorMw, anchorU, anchorV, aMh, Ph, Pa, rPx)) {
    return std::numeric_limits<double>::infinity();
  }
  return rPx.norm();
}
} // namespace hslam
