/*
 * H-SLAM for ViSP.
 */
/*!
  \file RectifierTarget.h
  \brief Choice of the rectified pinhole camera (crop, full, explicit, none) and the target-to-input pixel map.
*/
#ifndef HSLAM_RECTIFIER_TARGET_H
#define HSLAM_RECTIFIER_TARGET_H

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamCamera.h>

#include "camera/CameraModel.h"

#include <Eigen/Core>

namespace hslam
{

//! The ideal pinhole camera images are rectified to. Pixels, (0,0) = centre of the top-left pixel.
struct PinholeTarget {
  unsigned int width = 0;
  unsigned int height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;

  //! Point of the z = 1 plane seen by target pixel (x, y).
  Eigen::Vector2d pixelToNormalised(double x, double y) const { return Eigen::Vector2d((x - cx) / fx, (y - cy) / fy); }
};

/*!
  Where a point of the z = 1 plane appears in the input image, if it is usable for bilinear interpolation.
  \param uv : input pixel, clamped into [0, width-1] x [0, height-1].
  \return false when the point is outside the model's valid domain or further than a numerical tolerance
  (1e-6 px) outside that rectangle.
*/
VISP_EXPORT bool normalisedToSource(const CameraModel &model, unsigned int width, unsigned int height,
                                    const Eigen::Vector2d &m, Eigen::Vector2d &uv);

/*!
  Target pinhole camera of a calibration, following its rectification mode:
  - rectifyNone: the input intrinsics and size;
  - rectifyExplicit: the given intrinsics;
  - rectifyCrop: DSO's makeOptimalK_crop idea: stretch the two lines through the optical axis as far as the
    input image allows, then shrink, by 0.2 % steps, each side of the rectangle whose border rays leave the input
    through the matching image border (DSO shrinks the wider dimension instead), until every border ray is valid. For
  radially monotone models the valid region is star-shaped around the axis, so a valid border means every target pixel
  is valid.
  - rectifyFull: bounding box of the rays of every input border pixel (DSO leaves "full" unimplemented).
  \exception vpHSlamException::unsupported for rectifyFull when an input border pixel looks at or beyond 90
  degrees (or outside the model's domain), and for rectifyCrop when the optical axis is outside the input image
  or the shrinking does not converge.
*/
VISP_EXPORT PinholeTarget computeRectifiedTarget(const vpHSlamCamera &cam, const CameraModel &model);

} // namespace hslam

#endif
