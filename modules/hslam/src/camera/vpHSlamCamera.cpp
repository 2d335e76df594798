// vpHSlamCamera: construction, validation and projection through the internal camera models.
// The static load* functions live in CameraLoaders.cpp.
#include <visp3/hslam/vpHSlamCamera.h>

#include <visp3/core/vpException.h>
#include <visp3/hslam/vpHSlamException.h>

#include "camera/CameraModel.h"
#include "common/TextParsing.h"

#include <cmath>
#include <sstream>

namespace
{
//! Default camera: VGA with a 500 px focal length (about 65 degrees horizontal field of view).
constexpr unsigned int kDefaultWidth = 640;
constexpr unsigned int kDefaultHeight = 480;
constexpr double kDefaultFocal = 500.0;
//! Bilinear interpolation needs two rows and two columns.
constexpr unsigned int kMinImageSide = 2;
//! A viewing ray with z below this (unit ray) cannot be normalised to z = 1.
constexpr double kMinRayZ = 1e-12;
constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(int line, const std::string &what)
{
  hslam::throwAt(vpHSlamException::invalidCalibration, __FILE__, static_cast<std::size_t>(line), what);
}

std::string sizeString(unsigned int w, unsigned int h)
{
  return std::to_string(w) + "x" + std::to_string(h);
}

std::size_t expectedDistortionMin(vpHSlamCamera::Model model)
{
  switch (model) {
  case vpHSlamCamera::radialTangential:
    return 4;
  case vpHSlamCamera::equidistant:
    return 4;
  case vpHSlamCamera::fov:
    return 1;
  default:
    return 0;
  }
}

std::size_t expectedDistortionMax(vpHSlamCamera::Model model)
{
  return model == vpHSlamCamera::radialTangential ? 5 : expectedDistortionMin(model);
}
} // namespace

vpHSlamCamera::vpHSlamCamera()
    : vpHSlamCamera(pinhole, kDefaultWidth, kDefaultHeight, kDefaultFocal, kDefaultFocal, 0.5 * (kDefaultWidth - 1),
                    0.5 * (kDefaultHeight - 1))
{
}

vpHSlamCamera::vpHSlamCamera(Model model, unsigned int width, unsigned int height, double fx, double fy, double cx,
                             double cy, const std::vector<double> &distortion)
    : m_model(model), m_width(width), m_height(height), m_fx(fx), m_fy(fy), m_cx(cx), m_cy(cy),
      m_distortion(distortion), m_rectMode(rectifyNone), m_rectWidth(width), m_rectHeight(height), m_rectK()
{
  if (model != pinhole && model != radialTangential && model != equidistant && model != fov) {
    fail(__LINE__, "unknown camera model " + std::to_string(static_cast<int>(model)));
  }
  const std::string name = modelName(model) + " camera: ";
  if (width < kMinImageSide || height < kMinImageSide) {
    fail(__LINE__, name + "image size " + sizeString(width, height) + " must be at least 2x2 pixels");
  }
  if (!(std::isfinite(fx) && fx > 0.0 && std::isfinite(fy) && fy > 0.0)) {
    std::ostringstream os;
    os << name << "focal lengths must be positive and finite (fx = " << fx << ", fy = " << fy << ")";
    fail(__LINE__, os.str());
  }
  if (!(std::isfinite(cx) && std::isfinite(cy))) {
    std::ostringstream os;
    os << name << "principal point must be finite (cx = " << cx << ", cy = " << cy << ")";
    fail(__LINE__, os.str());
  }
  try {
    // ViSP inverts the focal lengths: a positive one too small for that (e.g. 1e-320) is refused there. Checked
    // here so that getIntrinsics() can never throw later.
    vpCameraParameters K;
    K.initPersProjWithoutDistortion(fx, fy, cx, cy);
  } catch (const vpException &e) {
    fail(__LINE__, name + "intrinsics refused by ViSP (" + e.getStringMessage() + ")");
  }
  const std::size_t nMin = expectedDistortionMin(model), nMax = expectedDistortionMax(model);
  if (distortion.size() < nMin || distortion.size() > nMax) {
    std::ostringstream os;
    os << name << "expects " << nMin;
    if (nMax != nMin) {
      os << " or " << nMax;
    }
    os << " distortion values, got " << distortion.size();
    fail(__LINE__, os.str());
  }
  for (std::size_t i = 0; i < distortion.size(); ++i) {
    if (!std::isfinite(distortion[i])) {
      fail(__LINE__, name + "distortion value " + std::to_string(i) + " is not finite");
    }
  }
  if (model == fov && !(distortion[0] > 0.0 && distortion[0] < kPi)) {
    std::ostringstream os;
    os << name << "omega = " << distortion[0] << " rad must lie in (0, pi)";
    fail(__LINE__, os.str());
  }
  // DSO's default: a pinhole input passes through, distorted inputs are cropped to their valid pinhole image.
  m_rectMode = model == pinhole ? rectifyNone : rectifyCrop;
}

vpCameraParameters vpHSlamCamera::getIntrinsics() const
{
  vpCameraParameters K;
  K.initPersProjWithoutDistortion(m_fx, m_fy, m_cx, m_cy);
  return K;
}

void vpHSlamCamera::setRectification(RectificationMode mode, unsigned int width, unsigned int height,
                                     const vpCameraParameters &K)
{
  if (mode != rectifyNone && mode != rectifyCrop && mode != rectifyFull && mode != rectifyExplicit) {
    fail(__LINE__, "unknown rectification mode " + std::to_string(static_cast<int>(mode)));
  }
  const unsigned int w = width == 0 ? m_width : width;
  const unsigned int h = height == 0 ? m_height : height;
  if (w < kMinImageSide || h < kMinImageSide) {
    fail(__LINE__, "rectified image size " + sizeString(w, h) + " must be at least 2x2 pixels");
  }
  if (mode == rectifyNone && (w != m_width || h != m_height)) {
    // DSO: "none" keeps the input intrinsics, which only describe an image of the input size.
    fail(__LINE__, "rectification 'none' needs the target size " + sizeString(w, h) + " to equal the input size " +
                       sizeString(m_width, m_height));
  }
  vpCameraParameters target;
  if (mode == rectifyExplicit) {
    const double px = K.get_px(), py = K.get_py(), u0 = K.get_u0(), v0 = K.get_v0();
    if (!(std::isfinite(px) && px > 0.0 && std::isfinite(py) && py > 0.0 && std::isfinite(u0) && std::isfinite(v0))) {
      std::ostringstream os;
      os << "explicit rectification needs positive finite focal lengths and a finite principal point (px = " << px
         << ", py = " << py << ", u0 = " << u0 << ", v0 = " << v0 << ")";
      fail(__LINE__, os.str());
    }
    try {
      target.initPersProjWithoutDistortion(px, py, u0, v0);
    } catch (const vpException &e) {
      fail(__LINE__, "explicit rectification intrinsics refused by ViSP (" + e.getStringMessage() + ")");
    }
  }
  m_rectMode = mode;
  m_rectWidth = w;
  m_rectHeight = h;
  m_rectK = target;
}

bool vpHSlamCamera::project(const vpColVector &cP, vpImagePoint &ip) const
{
  if (cP.size() != 3 && cP.size() != 4) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ": project() needs a 3-vector or a homogeneous 4-vector, got " +
                               std::to_string(cP.size()) + " values");
  }
  Eigen::Vector3d p(cP[0], cP[1], cP[2]);
  if (cP.size() == 4 && cP[3] != 0.0) {
    p /= cP[3];
  }
  Eigen::Vector2d uv;
  if (!hslam::makeCameraModel(*this)->project(p, uv)) {
    return false;
  }
  ip.set_uv(uv.x(), uv.y());
  return true;
}

bool vpHSlamCamera::unproject(const vpImagePoint &ip, vpColVector &ray) const
{
  Eigen::Vector3d r;
  if (!hslam::makeCameraModel(*this)->unproject(Eigen::Vector2d(ip.get_u(), ip.get_v()), r) || r.z() <= kMinRayZ) {
    return false;
  }
  ray.resize(3, false);
  ray[0] = r.x() / r.z();
  ray[1] = r.y() / r.z();
  ray[2] = 1.0;
  return true;
}

std::string vpHSlamCamera::modelName(Model model)
{
  switch (model) {
  case pinhole:
    return "Pinhole";
  case radialTangential:
    return "RadTan";
  case equidistant:
    return "EquiDistant";
  case fov:
    return "FOV";
  }
  return "Unknown";
}

std::string vpHSlamCamera::toString() const
{
  static const char *const modeNames[] = {"none", "crop", "full", "explicit"};
  std::ostringstream os;
  os << modelName(m_model) << " " << sizeString(m_width, m_height) << " fx=" << m_fx << " fy=" << m_fy << " cx=" << m_cx
     << " cy=" << m_cy;
  if (!m_distortion.empty()) {
    os << " dist=[";
    for (std::size_t i = 0; i < m_distortion.size(); ++i) {
      os << (i ? " " : "") << m_distortion[i];
    }
    os << "]";
  }
  os << " -> " << modeNames[m_rectMode] << " " << sizeString(m_rectWidth, m_rectHeight);
  if (m_rectMode == rectifyExplicit) {
    os << " fx=" << m_rectK.get_px() << " fy=" << m_rectK.get_py() << " cx=" << m_rectK.get_u0()
       << " cy=" << m_rectK.get_v0();
  }
  return os.str();
}
