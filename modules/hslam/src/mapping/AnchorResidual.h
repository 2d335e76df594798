/*
 * H-SLAM for ViSP.
 */
/*!
  \file AnchorResidual.h
  \brief The geometric residual that ties a re-used global point to the stored keyframe it came from.

  What it is for: re-use (vo-reuse, slam). A global point re-activated in the window (early adoption) or fused into
  an active point (late fusion) is re-hosted in a window keyframe with a new patch. Its photometric residuals only
  tie it to the window, and an inverse-depth prior in its new host only carries the old scale, so the window could
  drift away from the stored map it is re-observing (measured: vo-reuse lowered the ATE of the two-lap synthetic
  loop by 30 %, not half). The anchor measures the point where the stored map put it: projected into its old host
  keyframe (stored pose, held fixed), it must land on the old host pixel and have the old inverse depth.

  With the window point at host pixel (u, v), inverse depth rho, host pose hostMw (world-to-camera, left-perturbed
  like the window's states), P_h = K^-1 (u, v, 1) / rho and P_a = anchorMw hostMw^-1 P_h = (X, Y, Z):
  - r_px = (fx X / Z + cx - u_a, fy Y / Z + cy - v_a), energy pixelWeight huber(|r_px|, huberPx) (IRLS weight);
  - r_rho = 1 / Z - rho_a, energy idepthWeight r_rho^2.
  pixelWeight is in the window's energy units (grey levels squared) per squared pixel, so it says how much one
  anchor counts against the photometric residuals; idepthWeight is 1 / (the stored variance x
  globalMap.priorVarianceScale), as for the inverse-depth prior it replaces.

  Jacobians with respect to the host pose (twist, translation first) and rho: dP_a/dxi = -R_ah [I, -[P_h]x]
  (hostMw <- exp(xi) hostMw), dP_a/drho = -R_ah P_h / rho. The stored pose is a constant: it is not a state.

  Threading: free functions without state.
*/
#ifndef HSLAM_MAPPING_ANCHOR_RESIDUAL_H
#define HSLAM_MAPPING_ANCHOR_RESIDUAL_H

#include "features/ImagePyramid.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

namespace hslam
{
//! Where the stored map put a re-used point (see the file comment).
struct PointAnchor {
  bool active = false;
  SE3d anchorMw;            //!< stored keyframe's world-to-camera pose (held fixed)
  double u = 0., v = 0.;    //!< pixel in the stored keyframe
  double idepth = 0.;       //!< inverse depth in the stored keyframe
  double pixelWeight = 0.;  //!< energy per squared pixel
  double idepthWeight = 0.; //!< energy per squared inverse-depth unit
  double huberPx = 2.;      //!< Huber threshold of the pixel residual
};

//! Normal-equation blocks of one anchor (columns: host twist (6), rho).
struct AnchorLinearization {
  Eigen::Matrix<double, 6, 6> Hxx = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> bx = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> Hxr = Eigen::Matrix<double, 6, 1>::Zero(); //!< host twist x rho
  double Hrr = 0.;
  double br = 0.;
};

/*!
  Energy of \e anchor for a window point at host pixel (u, v) with inverse depth \e idepth and host pose
  \e hostMw; with \e lin non-null, also its blocks J^T W J and J^T W r. A point behind the stored camera or with a
  non-positive inverse depth gives 0 and no blocks (the photometric side decides about it).
*/
VISP_EXPORT double evaluateAnchor(const PinholeIntrinsics &K, const SE3d &hostMw, double u, double v, double idepth,
                                  const PointAnchor &anchor, AnchorLinearization *lin);

/*!
  Reprojection error, pixels, of a window point (host pixel (u, v), inverse depth \e idepth, host pose \e hostMw) in
  the stored keyframe \e anchorMw against the pixel (anchorU, anchorV); infinity when it is not in front of it.
*/
VISP_EXPORT double anchorPixelError(const PinholeIntrinsics &K, const SE3d &hostMw, double u, double v, double idepth,
                                    const SE3d &anchorMw, double anchorU, double anchorV);
} // namespace hslam

#endif
