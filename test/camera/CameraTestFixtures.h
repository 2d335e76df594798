// Camera descriptions shared by the camera tests and benchmarks: real calibrations of the datasets the project
// reads (EuRoC, TUM-VI, TUM monoVO) and a few synthetic ones that exercise specific code paths.
#ifndef HSLAM_TEST_CAMERA_TEST_FIXTURES_H
#define HSLAM_TEST_CAMERA_TEST_FIXTURES_H

#include <visp3/hslam/vpHSlamCamera.h>

namespace hslam_test
{
//! EuRoC MAV cam0 (radial-tangential, 4 coefficients), 752x480.
inline vpHSlamCamera eurocRadTan()
{
  return vpHSlamCamera(vpHSlamCamera::radialTangential, 752, 480, 458.654, 457.296, 367.215, 248.375,
                       {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
}

//! EuRoC's distortion on a VGA sensor (centred principal point).
inline vpHSlamCamera radTanVga()
{
  return vpHSlamCamera(vpHSlamCamera::radialTangential, 640, 480, 458.654, 457.296, 319.5, 239.5,
                       {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
}

//! A 5-parameter calibration (k3 != 0) at VGA, to exercise the k3 path.
inline vpHSlamCamera radTanK3()
{
  return vpHSlamCamera(vpHSlamCamera::radialTangential, 640, 480, 520.9, 521.0, 325.1, 249.7,
                       {0.2312, -0.7849, -0.0033, -0.0001, 0.9172});
}

//! k1 > 0 (pincushion): the valid region is barrel-shaped, so a crop must shrink from the centre lines.
inline vpHSlamCamera pincushionRadTan()
{
  return vpHSlamCamera(vpHSlamCamera::radialTangential, 640, 480, 500.0, 500.0, 330.0, 235.0,
                       {0.12, 0.02, 0.001, -0.0005});
}

//! TUM-VI cam0 (equidistant / Kannala-Brandt fisheye), 512x512.
inline vpHSlamCamera tumViEquidistant()
{
  return vpHSlamCamera(vpHSlamCamera::equidistant, 512, 512, 190.97, 190.98, 254.93, 256.90,
                       {0.0034823894, 0.000715034, -0.0020532361, 0.000202936});
}

//! TUM monoVO (FOV / ATAN model, intrinsics relative to the image size in its camera.txt), 1280x1024.
inline vpHSlamCamera tumMonoFov()
{
  return vpHSlamCamera(vpHSlamCamera::fov, 1280, 1024, 0.349 * 1280, 0.4655 * 1024, 0.4933 * 1280, 0.5 * 1024,
                       {0.9320});
}

//! Undistorted VGA camera.
inline vpHSlamCamera pinholeVga()
{
  return vpHSlamCamera(vpHSlamCamera::pinhole, 640, 480, 525.0, 524.0, 319.5, 239.5);
}
} // namespace hslam_test

#endif
