/*
 * H-SLAM for ViSP.
 */
/*!
  \file PointDescriptors.h
  \brief Oriented ORB descriptors at given pixels (paper section 3.1, descriptor sharing): every point the
  keyframe selects, FAST corner or DSO gradient pixel, gets a 256-bit descriptor at its own position.

  What it is for: descriptor sharing needs descriptors where the direct side put its points, not where an ORB
  detector would have put keypoints. The orientation is the intensity-centroid angle over a disc of radius 15 pixels
  (Rublee et al., ORB, 2011); the descriptor is OpenCV's rBRIEF (cv::ORB::compute) at that angle, level 0, patch 31.
  Points closer than kOrbBorderPx to the image border get no descriptor (the rotated pattern would leave the image).

  Threading: an object holds a cv::ORB and scratch buffers; use one per thread.
*/
#ifndef HSLAM_FEATURES_POINT_DESCRIPTORS_H
#define HSLAM_FEATURES_POINT_DESCRIPTORS_H

#include "features/BinaryDescriptor.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <opencv2/features2d.hpp>

#include <vector>

namespace hslam
{
//! Pixels this close to the border (or closer) get no descriptor: the 31x31 patch rotated by any angle must fit.
constexpr int kOrbBorderPx = 19;

class VISP_EXPORT PointDescriptors
{
public:
  PointDescriptors();

  /*!
    Descriptors at \e pixels (level-0 coordinates, (0,0) the centre of the top-left pixel) of the 8-bit image I.
    \param valid : per pixel, false when it lies too close to the border (its descriptor is then all zeros).
    \param anglesDeg : optional, the orientation used per pixel, degrees.
  */
  void compute(const vpImage<unsigned char> &I, const std::vector<cv::Point2f> &pixels,
               std::vector<OrbDescriptor> &descriptors, std::vector<bool> &valid,
               std::vector<float> *anglesDeg = nullptr);

  //! Intensity-centroid orientation at (u, v), degrees in [0, 360); the pixel must be kOrbBorderPx inside.
  static float orientation(const vpImage<unsigned char> &I, int u, int v);

private:
  cv::Ptr<cv::ORB> m_orb;
  std::vector<cv::KeyPoint> m_keypoints;
};
} // namespace hslam

#endif
