// Helpers shared by the tracking tests and benchmark: frames of the synthetic scene with their pyramid, reference
// points with exact inverse depth, reference features (corners with descriptors), ground-truth relative poses and pose
// errors.
#ifndef HSLAM_TEST_TRACKING_UTILS_H
#define HSLAM_TEST_TRACKING_UTILS_H

#include "features/CornerDetector.h"
#include "features/PointDescriptors.h"
#include "map/Frame.h"
#include "math/ViSPConversions.h"
#include "tracking/CoarseTracker.h"

#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace hslam_test
{
//! Default blur of the rendered frames, pixels (see makeFrame()).
constexpr double kTestBlurSigma = 1.0;

//! Level-0 intrinsics of the synthetic camera.
inline hslam::PinholeIntrinsics sceneIntrinsics(const vpHSlamSyntheticScene &scene)
{
  const vpCameraParameters cam = scene.getCameraParameters();
  hslam::PinholeIntrinsics K;
  K.fx = cam.get_px();
  K.fy = cam.get_py();
  K.cx = cam.get_u0();
  K.cy = cam.get_v0();
  return K;
}

/*!
  An 8-bit image of the scene's camera as a tracking frame (pyramid and raw image), with intensities gain * I + offset
  (as floats, not clipped); id, timestamp and pose are left to the caller. The rendering is blurred by a Gaussian of \e
  blurSigma pixels first (a lens point-spread function): the synthetic textures are sharper than a real camera's images,
  and bilinear interpolation of such edges alone leaves residuals of ~ 8 grey levels and a ~ 4 % contrast bias at the
  exact pose. Geometry (poses, depths) is unaffected.
*/
inline void makeFrameFromImage(const vpImage<unsigned char> &I8, const vpHSlamSyntheticScene &scene,
                               const vpHSlamParameters::Tracker &params, hslam::Frame &frame, double gain = 1.,
                               double offset = 0., double blurSigma = kTestBlurSigma)
{
  cv::Mat src(static_cast<int>(I8.getHeight()), static_cast<int>(I8.getWidth()), CV_8UC1, I8.bitmap);
  cv::Mat f, blurred;
  src.convertTo(f, CV_32F, gain, offset);
  if (blurSigma > 0.) {
    cv::GaussianBlur(f, blurred, cv::Size(0, 0), blurSigma, blurSigma, cv::BORDER_REPLICATE);
  } else {
    blurred = f;
  }
  vpImage<float> I(I8.getHeight(), I8.getWidth());
  for (int y = 0; y < blurred.rows; ++y) {
    std::copy(blurred.ptr<float>(y), blurred.ptr<float>(y) + blurred.cols, I[y]);
  }
  frame.pyramid.build(I, sceneIntrinsics(scene), params.maxPyramidLevels, params.minCoarsestPixels);
  frame.raw = I8;
}

//! Frame i of the scene, as makeFrameFromImage() makes it, with its id, timestamp and ground-truth pose.
inline void makeFrame(const vpHSlamSyntheticScene &scene, unsigned int i, const vpHSlamParameters::Tracker &params,
                      hslam::Frame &frame, double gain = 1., double offset = 0., double blurSigma = kTestBlurSigma)
{
  vpImage<unsigned char> I8;
  scene.render(i, I8);
  frame.id = static_cast<int>(i);
  frame.timestamp = scene.getTimestamp(i);
  frame.cMw = hslam::toSE3(scene.getPose(i).inverse());
  makeFrameFromImage(I8, scene, params, frame, gain, offset, blurSigma);
}

/*!
  About \e count points of frame \e i with exact inverse depth: in each cell of a regular grid, the pixel of largest
  gradient if its squared gradient exceeds \e minGradSq (intensity^2).
*/
inline std::vector<hslam::CoarseTrackerPoint> selectPoints(const vpHSlamSyntheticScene &scene, unsigned int i,
                                                           const hslam::Frame &frame, int count,
                                                           float minGradSq = 100.f)
{
  const hslam::PyramidLevel &L = frame.pyramid.level(0);
  const int cell = std::max(2, static_cast<int>(std::sqrt(static_cast<double>(L.width) * L.height / count)));
  std::vector<hslam::CoarseTrackerPoint> points;
  for (int y0 = 0; y0 + cell <= L.height; y0 += cell) {
    for (int x0 = 0; x0 + cell <= L.width; x0 += cell) {
      int best = -1;
      float bestG = minGradSq;
      for (int y = y0; y < y0 + cell; ++y) {
        for (int x = x0; x < x0 + cell; ++x) {
          const float g = L.gradSq[static_cast<size_t>(y * L.width + x)];
          if (g > bestG) {
            bestG = g;
            best = y * L.width + x;
          }
        }
      }
      if (best >= 0) {
        hslam::CoarseTrackerPoint p;
        p.u = static_cast<float>(best % L.width);
        p.v = static_cast<float>(best / L.width);
        p.idepth = static_cast<float>(1. / scene.depthAt(p.u, p.v, i));
        p.weight = 1.f;
        points.push_back(p);
      }
    }
  }
  return points;
}

/*!
  FAST corners of \e frame (frame \e i of the scene) with their exact 3D position in that camera and their ORB
  descriptor: the reference features of hybrid tracking.
*/
inline std::vector<hslam::ReferenceFeature> referenceFeatures(const vpHSlamSyntheticScene &scene, unsigned int i,
                                                              const hslam::Frame &frame)
{
  const hslam::PinholeIntrinsics K = sceneIntrinsics(scene);
  hslam::CornerOptions options;
  options.border = hslam::kOrbBorderPx + 1;
  std::vector<cv::Point2f> corners;
  hslam::detectCorners(frame.raw, options, corners);
  hslam::PointDescriptors describer;
  std::vector<hslam::OrbDescriptor> descriptors;
  std::vector<bool> valid;
  std::vector<float> angles;
  describer.compute(frame.raw, corners, descriptors, valid, &angles);
  std::vector<hslam::ReferenceFeature> features;
  for (size_t k = 0; k < corners.size(); ++k) {
    if (!valid[k]) {
      continue;
    }
    const double z = scene.depthAt(corners[k].x, corners[k].y, i);
    hslam::ReferenceFeature f;
    f.Xref = Eigen::Vector3d((corners[k].x - K.cx) / K.fx * z, (corners[k].y - K.cy) / K.fy * z, z);
    f.orb = descriptors[k];
    f.angleDeg = angles[k];
    features.push_back(f);
  }
  return features;
}

//! Exact reference-to-new transform newMref = cMw(new) * wMc(ref).
inline hslam::SE3d groundTruthNewMref(const vpHSlamSyntheticScene &scene, unsigned int ref, unsigned int target)
{
  return hslam::toSE3(scene.getPose(target).inverse() * scene.getPose(ref));
}

//! Translation error (scene units, metres) and rotation error (degrees) of an estimate.
inline void poseError(const hslam::SE3d &estimate, const hslam::SE3d &truth, double &translationError,
                      double &rotationErrorDeg)
{
  const hslam::SE3d E = estimate * truth.inverse();
  translationError = (estimate.translation() - truth.translation()).norm();
  rotationErrorDeg = E.log().tail<3>().norm() * 180. / M_PI;
}
} // namespace hslam_test

#endif
