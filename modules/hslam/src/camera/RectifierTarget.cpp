#include "camera/RectifierTarget.h"
#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace hslam
{
namespace
{
//! Numerical slack on the input-image rectangle: a target border ray traced to exactly u = 0 must stay valid
//! after its K round trip (errors ~1e-12 px).
constexpr double kSourceBorderTolerance = 1e-6;
//! Centre-line tracing: step along the line (z = 1 plane units) and furthest point looked at (~89 degrees).
constexpr double kLineTraceStep = 1e-2;
constexpr double kLineTraceMaxExtent = 60.0;
constexpr int kLineBisectionSteps = 60;
//! DSO shrinks an invalid side by 0.5 % per iteration; a finer 0.2 % gives a tighter crop for a few ms more.
constexpr double kCropShrinkFactor = 0.998;
constexpr int kCropMaxIterations = 20000;
//! A full-rectification ray must make less than ~89.9 degrees with the optical axis (unit-ray z above this).
constexpr double kFullMinRayZ = 1e-3;

[[noreturn]] void fail(int line, const std::string &what)
{
  throwAt(vpHSlamException::unsupported, __FILE__, static_cast<std::size_t>(line), what);
}

PinholeTarget fromNormalisedBox(unsigned int width, unsigned int height, double xmin, double xmax, double ymin,
                                double ymax)
{
  // DSO: pixel 0 sees xmin, pixel width-1 sees xmax.
  PinholeTarget t;
  t.width = width;
  t.height = height;
  t.fx = (width - 1) / (xmax - xmin);
  t.fy = (height - 1) / (ymax - ymin);
  t.cx = -xmin * t.fx;
  t.cy = -ymin * t.fy;
  return t;
}

//! Furthest s >= 0 such that every point of the segment [0, s] * dir maps inside the input image.
double traceLine(const CameraModel &model, unsigned int w, unsigned int h, const Eigen::Vector2d &dir)
{
  Eigen::Vector2d uv;
  double lo = 0.0;
  double hi = kLineTraceMaxExtent;
  for (double s = kLineTraceStep; s <= kLineTraceMaxExtent; s += kLineTraceStep) {
    if (!normalisedToSource(model, w, h, s * dir, uv)) {
      hi = s;
      break;
    }
    lo = s;
  }
  for (int k = 0; k < kLineBisectionSteps; ++k) {
    const double mid = 0.5 * (lo + hi);
    (normalisedToSource(model, w, h, mid * dir, uv) ? lo : hi) = mid;
  }
  return lo;
}

PinholeTarget cropTarget(const vpHSlamCamera &cam, const CameraModel &model)
{
  const unsigned int w = cam.getWidth(), h = cam.getHeight();
  const unsigned int tw = cam.getRectifiedWidth(), th = cam.getRectifiedHeight();
  Eigen::Vector2d uv;
  if (!normalisedToSource(model, w, h, Eigen::Vector2d::Zero(), uv)) {
    std::ostringstream os;
    os << "crop rectification of " << cam.toString() << ": the optical axis (principal point) is outside the image";
    fail(__LINE__, os.str());
  }
  // 1. DSO: stretch the centre lines as far as possible.
  double xmin = -traceLine(model, w, h, Eigen::Vector2d(-1.0, 0.0));
  double xmax = traceLine(model, w, h, Eigen::Vector2d(1.0, 0.0));
  double ymin = -traceLine(model, w, h, Eigen::Vector2d(0.0, -1.0));
  double ymax = traceLine(model, w, h, Eigen::Vector2d(0.0, 1.0));
  if (!(xmin < 0.0 && xmax > 0.0 && ymin < 0.0 && ymax > 0.0)) {
    fail(__LINE__, "crop rectification of " + cam.toString() + ": the principal point lies on the image border");
  }

  // 2. DSO: while border rays are invalid, shrink the offending sides. Unlike DSO, which shrinks only the wider
  // dimension when both have invalid rays, a side is blamed only when its rays leave the image through the
  // matching image border (left side: u < 0, top side: v < 0, ...): with a pincushion lens the corners leave
  // through the top and bottom, and shrinking the width there would waste most of the image.
  const auto probe = [&](double mx, double my, bool &outU, bool &outV) {
    Eigen::Vector2d raw;
    if (normalisedToSource(model, w, h, Eigen::Vector2d(mx, my), raw)) {
      return true;
    }
    if (!model.project(Eigen::Vector3d(mx, my, 1.0), raw)) {
      outU = outV = true; // outside the model's domain: blame both sides through this sample
      return false;
    }
    const bool u = !(raw.x() >= -kSourceBorderTolerance && raw.x() <= w - 1.0 + kSourceBorderTolerance);
    const bool v = !(raw.y() >= -kSourceBorderTolerance && raw.y() <= h - 1.0 + kSourceBorderTolerance);
    outU = outU || u;
    outV = outV || v;
    return false;
  };
  for (int it = 0;; ++it) {
    if (it >= kCropMaxIterations) {
      fail(__LINE__, "crop rectification of " + cam.toString() + " did not converge");
    }
    bool outLeft = false, outRight = false, outTop = false, outBottom = false;
    bool anyInvalid = false;
    for (unsigned int y = 0; y < th; ++y) {
      const double my = ymin + (ymax - ymin) * y / (th - 1);
      bool unusedV = false;
      anyInvalid = !probe(xmin, my, outLeft, unusedV) || anyInvalid;
      anyInvalid = !probe(xmax, my, outRight, unusedV) || anyInvalid;
    }
    for (unsigned int x = 0; x < tw; ++x) {
      const double mx = xmin + (xmax - xmin) * x / (tw - 1);
      bool unusedU = false;
      anyInvalid = !probe(mx, ymin, unusedU, outTop) || anyInvalid;
      anyInvalid = !probe(mx, ymax, unusedU, outBottom) || anyInvalid;
    }
    if (!anyInvalid) {
      break;
    }
    if (!(outLeft || outRight || outTop || outBottom)) {
      // Invalid rays that no side can be blamed for (a side crossing the other image border): shrink everything.
      outLeft = outRight = outTop = outBottom = true;
    }
    xmin *= outLeft ? kCropShrinkFactor : 1.0;
    xmax *= outRight ? kCropShrinkFactor : 1.0;
    ymin *= outTop ? kCropShrinkFactor : 1.0;
    ymax *= outBottom ? kCropShrinkFactor : 1.0;
  }
  return fromNormalisedBox(tw, th, xmin, xmax, ymin, ymax);
}

PinholeTarget fullTarget(const vpHSlamCamera &cam, const CameraModel &model)
{
  const unsigned int w = cam.getWidth(), h = cam.getHeight();
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin;
  double xmax = -xmin, ymax = -xmin;
  const auto include = [&](unsigned int u, unsigned int v) {
    Eigen::Vector3d ray;
    if (!model.unproject(Eigen::Vector2d(u, v), ray) || ray.z() < kFullMinRayZ) {
      std::ostringstream os;
      os << "full rectification of " << cam.toString() << ": input pixel (" << u << ", " << v
         << ") looks at or beyond 90 degrees from the optical axis (or outside the model's domain) and cannot be "
            "kept in a pinhole image; use crop or explicit rectification";
      fail(__LINE__, os.str());
    }
    xmin = std::min(xmin, ray.x() / ray.z());
    xmax = std::max(xmax, ray.x() / ray.z());
    ymin = std::min(ymin, ray.y() / ray.z());
    ymax = std::max(ymax, ray.y() / ray.z());
  };
  // The border of the input image maps to the border of its field of view (the models are one-to-one).
  for (unsigned int u = 0; u < w; ++u) {
    include(u, 0);
    include(u, h - 1);
  }
  for (unsigned int v = 0; v < h; ++v) {
    include(0, v);
    include(w - 1, v);
  }
  return fromNormalisedBox(cam.getRectifiedWidth(), cam.getRectifiedHeight(), xmin, xmax, ymin, ymax);
}
} // namespace

bool normalisedToSource(const CameraModel &model, unsigned int width, unsigned int height, const Eigen::Vector2d &m,
                        Eigen::Vector2d &uv)
{
  if (!model.project(Eigen::Vector3d(m.x(), m.y(), 1.0), uv)) {
    return false;
  }
  const double umax = width - 1.0, vmax = height - 1.0;
  // Written so that NaN coordinates are rejected.
  if (!(uv.x() >= -kSourceBorderTolerance && uv.x() <= umax + kSourceBorderTolerance &&
        uv.y() >= -kSourceBorderTolerance && uv.y() <= vmax + kSourceBorderTolerance)) {
    return false;
  }
  uv.x() = std::min(std::max(uv.x(), 0.0), umax);
  uv.y() = std::min(std::max(uv.y(), 0.0), vmax);
  return true;
}

PinholeTarget computeRectifiedTarget(const vpHSlamCamera &cam, const CameraModel &model)
{
  switch (cam.getRectificationMode()) {
  case vpHSlamCamera::rectifyNone: {
    PinholeTarget t;
    t.width = cam.getWidth();
    t.height = cam.getHeight();
    t.fx = cam.getFx();
    t.fy = cam.getFy();
    t.cx = cam.getCx();
    t.cy = cam.getCy();
    return t;
  }
  case vpHSlamCamera::rectifyExplicit: {
    const vpCameraParameters &K = cam.getExplicitRectifiedIntrinsics();
    PinholeTarget t;
    t.width = cam.getRectifiedWidth();
    t.height = cam.getRectifiedHeight();
    t.fx = K.get_px();
    t.fy = K.get_py();
    t.cx = K.get_u0();
    t.cy = K.get_v0();
    return t;
  }
  case vpHSlamCamera::rectifyCrop:
    return cropTarget(cam, model);
  case vpHSlamCamera::rectifyFull:
    return fullTarget(cam, model);
  }
  fail(__LINE__, "unknown rectification mode in " + cam.toString());
}

} // namespace hslam
