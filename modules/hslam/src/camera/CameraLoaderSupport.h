/*
 * H-SLAM for ViSP.
 */
// Shared by the calibration readers (CameraLoaders.cpp, CameraLoaderViSPXml.cpp, CameraLoaderYaml.cpp): build a
// vpHSlamCamera and set its rectification target, re-throwing validation errors with the file (and line) in front.
#ifndef HSLAM_CAMERA_LOADER_SUPPORT_H
#define HSLAM_CAMERA_LOADER_SUPPORT_H

#include <visp3/core/vpCameraParameters.h>
#include <visp3/hslam/vpHSlamCamera.h>

#include <cstddef>
#include <string>
#include <vector>

namespace hslam
{
constexpr std::size_t kIntrinsicCount = 4; // fx fy cx cy
constexpr std::size_t kSizeCount = 2;      // width height

//! vpHSlamCamera's constructor; its errors are re-thrown as "where: message" with their code kept.
vpHSlamCamera makeCamera(const std::string &where, vpHSlamCamera::Model model, unsigned int width, unsigned int height,
                         double fx, double fy, double cx, double cy, const std::vector<double> &distortion);

//! vpHSlamCamera::setRectification(); its errors are re-thrown as "where: message" with their code kept.
void applyRectification(vpHSlamCamera &cam, const std::string &where, vpHSlamCamera::RectificationMode mode,
                        unsigned int width, unsigned int height, const vpCameraParameters &K = vpCameraParameters());

//! DSO's default target: crop for distorted models, none for pinhole, at the input size.
void setDefaultRectification(vpHSlamCamera &cam, const std::string &where);
} // namespace hslam

#endif
