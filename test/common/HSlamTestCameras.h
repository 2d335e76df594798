// Test helper: the pinhole camera the geometry tests share (640x480, 500 px focal length, centred principal point).
#ifndef HSLAM_TEST_CAMERAS_H
#define HSLAM_TEST_CAMERAS_H

#include "features/ImagePyramid.h"

namespace hslam_test
{
//! fx = fy = 500 px, principal point at the centre of a 640x480 image.
inline hslam::PinholeIntrinsics vgaPinhole500()
{
  hslam::PinholeIntrinsics K;
  K.fx = K.fy = 500.;
  K.cx = 319.5;
  K.cy = 239.5;
  return K;
}
} // namespace hslam_test

#endif
