/*
 * H-SLAM for ViSP.
 */
/*!
  \file TagDetector.h
  \brief AprilTag sightings in a rectified image: id, metric pose, corners (ViSP's vpDetectorAprilTag).

  What it is for: the metric frame (map/MetricFrame.h) needs, for a keyframe, the poses of the described tag family's
  tags in that keyframe's camera, in metres. This wraps vpDetectorAprilTag: detection on the keyframe's rectified,
  photometrically raw 8-bit image (what a printed tag looks like), pose from the homography refined by virtual visual
  servoing (ViSP's default) with the rectified pinhole intrinsics.

  Refused sightings (never handed on): a tag whose corner reprojection error after the pose refinement is above
  kMaxProjectionErrorPx, one seen under kMinSidePx on a side (its pose is too noisy to scale a map with), and one
  touching the image border (a corner may be cut).

  Threading: one detector per thread (vpDetectorAprilTag keeps state). Given: the image. Hands back: sightings.
*/
#ifndef HSLAM_FEATURES_TAG_DETECTOR_H
#define HSLAM_FEATURES_TAG_DETECTOR_H

#include "math/SE3.h"

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamTag.h>

#include <Eigen/Core>

#include <array>
#include <memory>
#include <vector>

namespace hslam
{
class AprilTagBackend;

//! One tag seen in one image.
struct TagSighting {
  int id = -1;
  SE3d cMt; //!< tag frame to camera (metres): vpDetectorAprilTag::getPose()'s cMo
  //! image corners, pixels (the detector's order)
  std::array<Eigen::Vector2d, 4> corners = {Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(),
                                            Eigen::Vector2d::Zero()};
  double projectionErrorPx = 0.; //!< RMS corner reprojection error of cMt
};

class VISP_EXPORT TagDetector
{
public:
  //! Smallest side, in pixels, of a tag whose pose is used.
  static constexpr double kMinSidePx = 12.;
  //! Largest corner reprojection error (pixels) of a pose that is used.
  static constexpr double kMaxProjectionErrorPx = 1.5;
  //! Corners closer than this to the image border (pixels) refuse the sighting.
  static constexpr double kBorderPx = 2.;

  /*!
    \param tag : family and size (must be set).
    \param K : pinhole intrinsics of the images detect() will get.
    \exception vpHSlamException::invalidArgument when the tag is not set.
  */
  TagDetector(const vpHSlamTag &tag, const vpCameraParameters &K);
  ~TagDetector();
  TagDetector(const TagDetector &) = delete;
  TagDetector &operator=(const TagDetector &) = delete;

  //! Sightings of the family's tags in \e I (only the tag's id when it has one); refused ones are left out.
  std::vector<TagSighting> detect(const vpImage<unsigned char> &I);

  //! Tags found by the last detect() before the checks above (for statistics and display).
  unsigned int lastRawDetections() const { return m_lastRaw; }

private:
  vpHSlamTag m_tag;
  vpCameraParameters m_K;
  std::unique_ptr<AprilTagBackend> m_detector; //!< vpDetectorAprilTag, in the plug-in libvisp_hslam_tag
  unsigned int m_lastRaw = 0;
};
} // namespace hslam

#endif
