/*
 * H-SLAM for ViSP.
 */
//! \file AprilTagPlugin.h  AprilTag detection by a plug-in loaded on first use (libvisp_hslam_tag).
#ifndef HSLAM_FEATURES_APRIL_TAG_PLUGIN_H
#define HSLAM_FEATURES_APRIL_TAG_PLUGIN_H

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImagePoint.h>

#include <cstddef>
#include <string>
#include <vector>

namespace hslam
{
//! One tag found in an image, as the detector gives it.
struct RawTagDetection {
  int id = -1;
  std::vector<vpImagePoint> corners; //!< the detector's corners (4), pixels
};

/*!
  ViSP's vpDetectorAprilTag behind an interface, implemented by the plug-in libvisp_hslam_tag
  (modules/hslam/plugins/tag/), which TagDetector loads the first time a tag is described (common/PluginLoader.h:
  ViSP's detection module links ViSP's and OpenCV's image and video I/O, about 200 shared libraries that every
  program would load at start). Nothing crosses the boundary as an exception: failures come back as false with a
  message.
*/
class AprilTagBackend
{
public:
  virtual ~AprilTagBackend() = default;
  //! The tags in \e I into \e tags (empty when none); false with \e error set when the detector failed.
  virtual bool detect(const vpImage<unsigned char> &I, std::vector<RawTagDetection> &tags, std::string &error) = 0;
  //! Pose of the \e index-th tag of the last detect(), for a black square of \e size metres seen by \e K: cMt,
  //! the tag's frame in the camera (vpDetectorAprilTag::getPose()'s cMo); false when the detector gives none.
  virtual bool pose(std::size_t index, double size, const vpCameraParameters &K, vpHomogeneousMatrix &cMt) = 0;
};

//! Name of the plug-in's factory: AprilTagBackend *(const char *family, std::string *error), null on failure
//! (unknown family, or a ViSP without its AprilTag detector).
constexpr const char *kTagPluginFactory = "hslamCreateAprilTagDetector";
//! File name of the plug-in, looked for beside libvisp_hslam (or at HSLAM_TAG_PLUGIN), then on the loader's path.
constexpr const char *kTagPluginFile = "libvisp_hslam_tag.so";
} // namespace hslam

#endif
