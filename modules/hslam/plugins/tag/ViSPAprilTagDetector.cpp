/*
 * H-SLAM for ViSP.
 */
// The tag plug-in (libvisp_hslam_tag): AprilTagBackend on ViSP's vpDetectorAprilTag. Loaded by TagDetector on first
// use, so that only programs that describe a tag load ViSP's detection module and what it links
// (src/features/AprilTagPlugin.h says why).
#include "features/AprilTagPlugin.h"

#include <visp3/core/vpConfig.h>
#ifdef VISP_HAVE_APRILTAG
#include <visp3/detection/vpDetectorAprilTag.h>
#endif

#include <exception>

namespace
{
#ifdef VISP_HAVE_APRILTAG
class ViSPAprilTagDetector final : public hslam::AprilTagBackend
{
public:
  explicit ViSPAprilTagDetector(vpDetectorAprilTag::vpAprilTagFamily family)
      : m_detector(family, vpDetectorAprilTag::HOMOGRAPHY_VIRTUAL_VS)
  {
    m_detector.setAprilTagNbThreads(1);
    // Full resolution for the quads: keyframes only, and corner accuracy is what sets the scale.
    m_detector.setAprilTagQuadDecimate(1.f);
  }

  bool detect(const vpImage<unsigned char> &I, std::vector<hslam::RawTagDetection> &tags, std::string &error) override
  {
    tags.clear();
    try {
      if (!m_detector.detect(I)) {
        return true;
      }
      const std::vector<int> ids = m_detector.getTagsId();
      const std::vector<std::vector<vpImagePoint>> corners = m_detector.getTagsCorners();
      for (std::size_t i = 0; i < ids.size() && i < corners.size(); ++i) {
        tags.push_back(hslam::RawTagDetection{ids[i], corners[i]});
      }
      return true;
    } catch (const std::exception &e) {
      error = e.what();
      return false;
    }
  }

  bool pose(std::size_t index, double size, const vpCameraParameters &K, vpHomogeneousMatrix &cMt) override
  {
    try {
      double projectionError = 0.; // asked for as before the plug-in, so that the pose is computed the same way
      return m_detector.getPose(index, size, K, cMt, nullptr, &projectionError, nullptr);
    } catch (const std::exception &) {
      return false;
    }
  }

private:
  vpDetectorAprilTag m_detector;
};

bool familyOf(const std::string &name, vpDetectorAprilTag::vpAprilTagFamily &family)
{
  if (name == "tag36h11") {
    family = vpDetectorAprilTag::TAG_36h11;
  } else if (name == "tag25h9") {
    family = vpDetectorAprilTag::TAG_25h9;
  } else if (name == "tag16h5") {
    family = vpDetectorAprilTag::TAG_16h5;
  } else if (name == "tagCircle21h7") {
    family = vpDetectorAprilTag::TAG_CIRCLE21h7;
  } else {
    return false;
  }
  return true;
}
#endif
} // namespace

//! The plug-in's factory (hslam::kTagPluginFactory): a detector of \e family, or null with \e error set.
extern "C" __attribute__((visibility("default"))) hslam::AprilTagBackend *
hslamCreateAprilTagDetector(const char *family, std::string *error)
{
#ifdef VISP_HAVE_APRILTAG
  try {
    vpDetectorAprilTag::vpAprilTagFamily f;
    if (!familyOf(family, f)) {
      *error = "unknown family '" + std::string(family) + "'";
      return nullptr;
    }
    return new ViSPAprilTagDetector(f);
  } catch (const std::exception &e) {
    *error = e.what();
    return nullptr;
  }
#else
  (void)family;
  *error = "this ViSP was built without its AprilTag detector (VISP_HAVE_APRILTAG)";
  return nullptr;
#endif
}
