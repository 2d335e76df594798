#include "features/TagDetector.h"

#include "common/PluginLoader.h"
#include "features/AprilTagPlugin.h"
#include "features/ImagePyramid.h"
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hslam
{
TagDetector::TagDetector(const vpHSlamTag &tag, const vpCameraParameters &K) : m_tag(tag), m_K(K)
{
  if (!tag.isSet()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "tag detector: no tag described");
  }
#ifndef VISP_HAVE_APRILTAG
  throw vpHSlamException(vpHSlamException::unsupported,
                         "tag detector: this ViSP was built without its AprilTag detector (VISP_HAVE_APRILTAG)");
#else
  using Factory = AprilTagBackend *(*)(const char *, std::string *);
  std::string error;
  const auto factory = loadPluginFunction<Factory>(kTagPluginFile, kTagPluginFactory, "HSLAM_TAG_PLUGIN", error);
  if (factory == nullptr) {
    throw vpHSlamException(vpHSlamException::unsupported, "tag detector: tags are detected by a plug-in: " + error);
  }
  m_detector.reset(factory(tag.getFamily().c_str(), &error));
  if (!m_detector) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "tag detector: " + error);
  }
#endif
}

TagDetector::~TagDetector() = default;

std::vector<TagSighting> TagDetector::detect(const vpImage<unsigned char> &I)
{
  std::vector<TagSighting> out;
  m_lastRaw = 0;
#ifndef VISP_HAVE_APRILTAG
  (void)I;
  return out;
#else
  std::vector<RawTagDetection> tags;
  std::string error;
  if (I.getSize() == 0 || !m_detector->detect(I, tags, error)) {
    return out; // an image the detector fails on has no sighting; tracking and mapping go on
  }
  m_lastRaw = static_cast<unsigned int>(tags.size());
  const double w = I.getWidth(), h = I.getHeight();
  for (size_t i = 0; i < tags.size(); ++i) {
    const std::vector<vpImagePoint> &corners = tags[i].corners;
    if ((m_tag.hasId() && tags[i].id != m_tag.getId()) || corners.size() != 4) {
      continue;
    }
    TagSighting s;
    s.id = tags[i].id;
    bool inside = true;
    double minSide = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < 4; ++k) {
      const vpImagePoint &p = corners[k], &q = corners[(k + 1) % 4];
      s.corners[k] = Eigen::Vector2d(p.get_u(), p.get_v());
      inside = inside && p.get_u() >= kBorderPx && p.get_v() >= kBorderPx && p.get_u() <= w - 1 - kBorderPx &&
               p.get_v() <= h - 1 - kBorderPx;
      minSide = std::min(minSide, std::hypot(p.get_u() - q.get_u(), p.get_v() - q.get_v()));
    }
    if (!inside || minSide < kMinSidePx) {
      continue;
    }
    vpHomogeneousMatrix cMt;
    if (!m_detector->pose(i, m_tag.getSize(), m_K, cMt)) {
      continue;
    }
    // getPose reports the residual of its virtual visual servoing as a sum over the corners' normalised
    // coordinates; recompute the RMS in pixels from the pose to have a unit a threshold can be written in.
    const double half = 0.5 * m_tag.getSize();
    const double tagCorners[4][2] = {{-half, half}, {half, half}, {half, -half}, {-half, -half}};
    const SE3d pose = toSE3(cMt);
    const PinholeIntrinsics pinhole{m_K.get_px(), m_K.get_py(), m_K.get_u0(), m_K.get_v0()};
    double sq = 0.;
    bool front = true;
    std::array<Eigen::Vector2d, 4> projected;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d X = pose * Eigen::Vector3d(tagCorners[k][0], tagCorners[k][1], 0.);
      front = front && X.z() > 0.;
      projected[k] = pinhole.project(X);
    }
    // The detector's corner order is fixed relative to the tag; match each projected corner to the nearest
    // detected one so the check does not depend on it.
    for (int k = 0; k < 4; ++k) {
      double best = std::numeric_limits<double>::infinity();
      for (int j = 0; j < 4; ++j) {
        best = std::min(best, (projected[k] - s.corners[j]).squaredNorm());
      }
      sq += best;
    }
    s.projectionErrorPx = std::sqrt(sq / 4.);
    if (!front || !(s.projectionErrorPx <= kMaxProjectionErrorPx)) {
      continue;
    }
    s.cMt = pose;
    out.push_back(s);
  }
  return out;
#endif
}
} // namespace hslam
