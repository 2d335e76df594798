#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamRectifier.h>

#include <visp3/core/vpException.h>

#include "camera/CameraModel.h"
#include "camera/RectifierRemap.h"
#include "camera/RectifierTarget.h"

#include <cstring>
#include <string>

namespace
{
//! A rectified point needs a ray with z above this (unit ray) to be normalised.
constexpr double kMinRayZ = 1e-12;

std::string sizeString(unsigned int w, unsigned int h)
{
  return std::to_string(w) + "x" + std::to_string(h);
}
} // namespace

struct vpHSlamRectifier::Impl {
  vpHSlamCamera camera;
  std::unique_ptr<hslam::CameraModel> model;
  hslam::PinholeTarget target;
  hslam::RectifierRemap remap;
  bool passThrough = false;

  explicit Impl(const vpHSlamCamera &cam) : camera(cam), model(hslam::makeCameraModel(cam))
  {
    target = hslam::computeRectifiedTarget(camera, *model);
    // DSO's "passthrough": a pinhole input whose target is itself needs no interpolation.
    passThrough = camera.getModel() == vpHSlamCamera::pinhole && target.width == camera.getWidth() &&
                  target.height == camera.getHeight() && target.fx == camera.getFx() && target.fy == camera.getFy() &&
                  target.cx == camera.getCx() && target.cy == camera.getCy();
    if (passThrough) {
      return;
    }
    const hslam::CameraModel &m = *model;
    const hslam::PinholeTarget &t = target;
    const unsigned int w = camera.getWidth(), h = camera.getHeight();
    remap.build(t.width, t.height, w, h, [&m, &t, w, h](unsigned int x, unsigned int y, double &u, double &v) {
      Eigen::Vector2d uv;
      if (!hslam::normalisedToSource(m, w, h, t.pixelToNormalised(x, y), uv)) {
        return false;
      }
      u = uv.x();
      v = uv.y();
      return true;
    });
  }

  Impl(const Impl &other)
      : camera(other.camera), model(hslam::makeCameraModel(other.camera)), target(other.target), remap(other.remap),
        passThrough(other.passThrough)
  {
  }

  template <typename Type> void rectify(const vpImage<Type> &I, vpImage<Type> &Irect) const
  {
    if (I.getWidth() != camera.getWidth() || I.getHeight() != camera.getHeight()) {
      throw vpHSlamException(vpHSlamException::invalidImage, std::string(__FILE__) + ": rectify() got a " +
                                                                 sizeString(I.getWidth(), I.getHeight()) +
                                                                 " image but the calibration is for " +
                                                                 sizeString(camera.getWidth(), camera.getHeight()));
    }
    if (&I == &Irect) {
      if (passThrough) {
        return;
      }
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             std::string(__FILE__) + ": rectify() cannot work in place (input and output are the "
                                                     "same image)");
    }
    if (Irect.getWidth() != target.width || Irect.getHeight() != target.height) {
      Irect.resize(target.height, target.width);
    }
    if (passThrough) {
      std::memcpy(Irect.bitmap, I.bitmap, sizeof(Type) * I.getSize());
    } else {
      remap.apply(I.bitmap, Irect.bitmap);
    }
  }
};

vpHSlamRectifier::vpHSlamRectifier(const vpHSlamCamera &camera) : m_impl(std::make_unique<Impl>(camera))
{
  try {
    // The target intrinsics were computed from the calibration; one ViSP cannot invert is refused here, so that
    // getCameraParameters() never throws later.
    vpCameraParameters K;
    K.initPersProjWithoutDistortion(m_impl->target.fx, m_impl->target.fy, m_impl->target.cx, m_impl->target.cy);
  } catch (const vpException &e) {
    throw vpHSlamException(vpHSlamException::invalidCalibration,
                           std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                               ": rectified intrinsics refused by ViSP (" + e.getStringMessage() + ")");
  }
}

vpHSlamRectifier::vpHSlamRectifier(const vpHSlamRectifier &other) : m_impl(std::make_unique<Impl>(*other.m_impl)) {}

vpHSlamRectifier::vpHSlamRectifier(vpHSlamRectifier &&other) noexcept = default;

vpHSlamRectifier &vpHSlamRectifier::operator=(const vpHSlamRectifier &other)
{
  if (this != &other) {
    m_impl = std::make_unique<Impl>(*other.m_impl);
  }
  return *this;
}

vpHSlamRectifier &vpHSlamRectifier::operator=(vpHSlamRectifier &&other) noexcept = default;

vpHSlamRectifier::~vpHSlamRectifier() = default;

void vpHSlamRectifier::rectify(const vpImage<unsigned char> &I, vpImage<unsigned char> &Irect) const
{
  m_impl->rectify(I, Irect);
}

void vpHSlamRectifier::rectify(const vpImage<float> &I, vpImage<float> &Irect) const
{
  m_impl->rectify(I, Irect);
}

vpCameraParameters vpHSlamRectifier::getCameraParameters() const
{
  vpCameraParameters K;
  K.initPersProjWithoutDistortion(m_impl->target.fx, m_impl->target.fy, m_impl->target.cx, m_impl->target.cy);
  return K;
}

unsigned int vpHSlamRectifier::getWidth() const
{
  return m_impl->target.width;
}

unsigned int vpHSlamRectifier::getHeight() const
{
  return m_impl->target.height;
}

const vpHSlamCamera &vpHSlamRectifier::getCamera() const
{
  return m_impl->camera;
}

bool vpHSlamRectifier::isPassThrough() const
{
  return m_impl->passThrough;
}

unsigned int vpHSlamRectifier::getInvalidPixelCount() const
{
  return m_impl->passThrough ? 0u : static_cast<unsigned int>(m_impl->remap.invalidPixels().size());
}

void vpHSlamRectifier::getValidMask(vpImage<bool> &mask) const
{
  mask.resize(m_impl->target.height, m_impl->target.width, true);
  if (!m_impl->passThrough) {
    for (const uint32_t k : m_impl->remap.invalidPixels()) {
      mask.bitmap[k] = false;
    }
  }
}

bool vpHSlamRectifier::rectifyPoint(const vpImagePoint &ipInput, vpImagePoint &ipRect) const
{
  Eigen::Vector3d ray;
  if (!m_impl->model->unproject(Eigen::Vector2d(ipInput.get_u(), ipInput.get_v()), ray) || ray.z() <= kMinRayZ) {
    return false;
  }
  const hslam::PinholeTarget &t = m_impl->target;
  ipRect.set_uv(t.fx * ray.x() / ray.z() + t.cx, t.fy * ray.y() / ray.z() + t.cy);
  return true;
}

bool vpHSlamRectifier::distortPoint(const vpImagePoint &ipRect, vpImagePoint &ipInput) const
{
  const Eigen::Vector2d m = m_impl->target.pixelToNormalised(ipRect.get_u(), ipRect.get_v());
  Eigen::Vector2d uv;
  if (!m_impl->model->project(Eigen::Vector3d(m.x(), m.y(), 1.0), uv)) {
    return false;
  }
  ipInput.set_uv(uv.x(), uv.y());
  return true;
}
