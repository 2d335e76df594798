/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlamLiveView.h>

#include <visp3/core/vpFont.h>
#include <visp3/core/vpImageConvert.h>
#include <visp3/core/vpImageDraw.h>
#include <visp3/core/vpMeterPixelConversion.h>
#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace
{
constexpr unsigned int kDefaultTopViewWidth = 360;
constexpr unsigned int kMinTopViewWidth = 64;
constexpr unsigned int kFontHeight = 16;
constexpr unsigned int kStatusBand = 22; //!< height of the dark band behind the status line, pixels
constexpr int kPointRadius = 2;
constexpr unsigned int kMatchCrossSize = 7; //!< descriptor matches: cross width and height, pixels
constexpr double kMarginFraction = 0.08;    //!< top view: free border around the trajectory
const vpColor kPanelBackground(32, 32, 32);
const vpColor kTrajectoryColour(60, 200, 60);
const vpColor kKeyframeColour(80, 140, 255);
const vpColor kCameraColour(255, 60, 60);
const vpColor kTextColour(255, 255, 255);
//! Descriptor matches: magenta, a hue the inverse-depth ramp of the points (blue, cyan, green, yellow, red) never
//! takes.
const vpColor kMatchColour(255, 0, 255);

//! The tag and the world axes: x red, y green, z blue (ViSP's frame colours).
const vpColor kTagColour(255, 200, 0);

//! ViSP's bitmap font (its TrueType path is unreliable in 3.5, see TrajectoryPlot.cpp).
vpFont &font()
{
  static vpFont f(kFontHeight, vpFont::GENERIC_MONOSPACE);
  return f;
}

//! Fills a rectangle (vpImageDraw has no filled rectangle in ViSP 3.5).
void fill(vpImage<vpRGBa> &I, unsigned int u0, unsigned int v0, unsigned int w, unsigned int h, const vpColor &c)
{
  const vpRGBa rgba(c.R, c.G, c.B);
  for (unsigned int v = v0; v < std::min(I.getHeight(), v0 + h); ++v) {
    for (unsigned int u = u0; u < std::min(I.getWidth(), u0 + w); ++u) {
      I[v][u] = rgba;
    }
  }
}

/*!
  With a metric frame: where the system places the tag, projected by the current pose (its black square, yellow) and
  the output frame's axes at its origin, one tag size long (x red, y green, z blue); nothing otherwise. In the tag's
  frame the origin is the tag's centre, so a drift of the estimate shows as the drawing sliding off the printed tag.
*/
void drawWorldFrame(const vpHSlam &slam, vpImage<vpRGBa> &canvas)
{
  const vpHSlam::WorldFrame world = slam.getWorldFrame();
  const vpHSlamTag tag = slam.getTag();
  if (!world.metric || !tag.isSet()) {
    return;
  }
  const vpHomogeneousMatrix cMw = slam.get_cMw();
  const vpCameraParameters K = slam.getCameraParameters();
  const double a = tag.getSize();
  bool visible = true;
  auto project = [&](double x, double y, double z) {
    const vpColVector X = cMw * vpColVector({x, y, z, 1.});
    visible = visible && X[2] > 0.;
    vpImagePoint ip;
    vpMeterPixelConversion::convertPoint(K, X[0] / X[2], X[1] / X[2], ip);
    return ip;
  };
  const vpImagePoint o = project(0., 0., 0.), ax = project(a, 0., 0.), ay = project(0., a, 0.), az = project(0., 0., a);
  std::vector<vpImagePoint> square;
  if (world.tagFrame) {
    const double h = 0.5 * a;
    square = {project(-h, -h, 0.), project(h, -h, 0.), project(h, h, 0.), project(-h, h, 0.)};
  }
  if (!visible) {
    return;
  }
  for (size_t k = 0; k < square.size(); ++k) {
    vpImageDraw::drawLine(canvas, square[k], square[(k + 1) % square.size()], kTagColour, 2);
  }
  vpImageDraw::drawArrow(canvas, o, ax, vpColor::red, 4, 2, 2);
  vpImageDraw::drawArrow(canvas, o, ay, vpColor::green, 4, 2, 2);
  vpImageDraw::drawArrow(canvas, o, az, vpColor::blue, 4, 2, 2);
}

void drawPoints(const vpHSlam &slam, vpImage<vpRGBa> &canvas)
{
  const std::vector<vpColVector> points = slam.getActivePoints();
  const vpHomogeneousMatrix cMw = slam.get_cMw();
  const vpCameraParameters K = slam.getCameraParameters();
  std::vector<vpImagePoint> pixels;
  std::vector<double> idepths;
  for (const vpColVector &wX : points) {
    const double x = cMw[0][0] * wX[0] + cMw[0][1] * wX[1] + cMw[0][2] * wX[2] + cMw[0][3];
    const double y = cMw[1][0] * wX[0] + cMw[1][1] * wX[1] + cMw[1][2] * wX[2] + cMw[1][3];
    const double z = cMw[2][0] * wX[0] + cMw[2][1] * wX[1] + cMw[2][2] * wX[2] + cMw[2][3];
    if (!(z > 0.)) {
      continue;
    }
    vpImagePoint ip;
    vpMeterPixelConversion::convertPoint(K, x / z, y / z, ip);
    if (ip.get_u() < 0 || ip.get_v() < kStatusBand || ip.get_u() >= slam.getWidth() || ip.get_v() >= slam.getHeight()) {
      continue;
    }
    pixels.push_back(ip);
    idepths.push_back(1. / z);
  }
  if (idepths.empty()) {
    return;
  }
  std::vector<double> sorted = idepths;
  std::sort(sorted.begin(), sorted.end());
  const double lo = sorted[sorted.size() / 20];
  const double hi = sorted[sorted.size() - 1 - sorted.size() / 20];
  const double range = std::max(hi - lo, 1e-12);
  for (std::size_t k = 0; k < pixels.size(); ++k) {
    const vpRGBa c = vpHSlamLiveView::inverseDepthColor((idepths[k] - lo) / range);
    vpImageDraw::drawCircle(canvas, pixels[k], kPointRadius, vpColor(c.R, c.G, c.B), 2);
  }
}

//! The keypoints matched by ORB descriptor in the last frame (rectified pixels, as the image): one cross each.
void drawDescriptorMatches(const std::vector<vpImagePoint> &matches, vpImage<vpRGBa> &canvas, unsigned int width,
                           unsigned int height)
{
  for (const vpImagePoint &ip : matches) {
    if (ip.get_u() < 0 || ip.get_v() < kStatusBand || ip.get_u() >= width || ip.get_v() >= height) {
      continue;
    }
    vpImageDraw::drawCross(canvas, ip, kMatchCrossSize, kMatchColour, 1);
  }
}

void drawTopView(const vpHSlam &slam, vpImage<vpRGBa> &canvas, unsigned int u0, unsigned int width)
{
  const unsigned int height = canvas.getHeight();
  fill(canvas, u0, 0, width, height, kPanelBackground);
  font().drawText(canvas, "top view (x, z)", vpImagePoint(4, u0 + 6), kTextColour);
  const vpHSlamTrajectory trajectory = slam.getTrajectory();
  const std::vector<vpHSlam::Keyframe> keyframes = slam.getKeyframes();
  if (trajectory.empty() && keyframes.empty()) {
    return;
  }
  // World x to the right, world z upwards in the picture; one scale for both axes.
  double xMin = 1e300, xMax = -1e300, zMin = 1e300, zMax = -1e300;
  auto extend = [&](const vpHomogeneousMatrix &wMc) {
    xMin = std::min(xMin, wMc[0][3]);
    xMax = std::max(xMax, wMc[0][3]);
    zMin = std::min(zMin, wMc[2][3]);
    zMax = std::max(zMax, wMc[2][3]);
  };
  for (const vpHomogeneousMatrix &wMc : trajectory.getPoses()) {
    extend(wMc);
  }
  for (const vpHSlam::Keyframe &kf : keyframes) {
    extend(kf.wMc);
  }
  const double span = std::max({xMax - xMin, zMax - zMin, 1e-6});
  const double usable = (1. - 2. * kMarginFraction) * std::min(width, height - kStatusBand);
  const double scale = usable / span;
  const double uc = u0 + 0.5 * width, vc = kStatusBand + 0.5 * (height - kStatusBand);
  const double xm = 0.5 * (xMin + xMax), zm = 0.5 * (zMin + zMax);
  auto toPixel = [&](double x, double z) { return vpImagePoint(vc - scale * (z - zm), uc + scale * (x - xm)); };

  const std::vector<vpHomogeneousMatrix> &poses = trajectory.getPoses();
  for (std::size_t i = 1; i < poses.size(); ++i) {
    vpImageDraw::drawLine(canvas, toPixel(poses[i - 1][0][3], poses[i - 1][2][3]),
                          toPixel(poses[i][0][3], poses[i][2][3]), kTrajectoryColour, 1);
  }
  for (const vpHSlam::Keyframe &kf : keyframes) {
    const vpImagePoint p = toPixel(kf.wMc[0][3], kf.wMc[2][3]);
    vpImageDraw::drawRectangle(canvas, vpRect(p.get_u() - 3, p.get_v() - 3, 7, 7), kKeyframeColour, kf.inWindow, 1);
  }
  if (slam.hasPose()) {
    const vpHomogeneousMatrix wMc = slam.get_cMw().inverse();
    const vpImagePoint p = toPixel(wMc[0][3], wMc[2][3]);
    // Viewing direction: the camera's optical axis (third column of the rotation) in the x-z plane.
    const double dx = wMc[0][2], dz = wMc[2][2];
    const double norm = std::max(std::hypot(dx, dz), 1e-9);
    const vpImagePoint tip(p.get_i() - 18. * dz / norm, p.get_j() + 18. * dx / norm);
    vpImageDraw::drawCircle(canvas, p, 5, kCameraColour, 2);
    vpImageDraw::drawLine(canvas, p, tip, kCameraColour, 2);
  }
}
} // namespace

vpHSlamLiveView::vpHSlamLiveView() : m_topViewWidth(kDefaultTopViewWidth) {}

void vpHSlamLiveView::setTopViewWidth(unsigned int width)
{
  if (width != 0 && width < kMinTopViewWidth) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "vpHSlamLiveView: top view width " + std::to_string(width) + " below " +
                               std::to_string(kMinTopViewWidth) + " pixels (0 hides it)");
  }
  m_topViewWidth = width;
}

vpRGBa vpHSlamLiveView::inverseDepthColor(double x)
{
  // Jet-like ramp, reversed so that near (large inverse depth) is red and far is blue.
  x = 1. - std::min(1., std::max(0., std::isfinite(x) ? x : 0.));
  const double r = std::min(1., std::max(0., 1.5 - std::abs(4. * x - 1.)));
  const double g = std::min(1., std::max(0., 1.5 - std::abs(4. * x - 2.)));
  const double b = std::min(1., std::max(0., 1.5 - std::abs(4. * x - 3.)));
  return vpRGBa(static_cast<unsigned char>(255. * r), static_cast<unsigned char>(255. * g),
                static_cast<unsigned char>(255. * b));
}

void vpHSlamLiveView::draw(const vpHSlam &slam, unsigned int frameIndex, double fps, vpImage<vpRGBa> &canvas,
                           const std::string &hint) const
{
  vpImage<unsigned char> I;
  slam.getRectifiedImage(I);
  const unsigned int w = slam.getWidth(), h = slam.getHeight();
  if (I.getWidth() != w || I.getHeight() != h) {
    I.resize(h, w, 0); // nothing tracked yet: a black image of the right size
  }
  canvas.resize(h, w + m_topViewWidth);
  for (unsigned int v = 0; v < h; ++v) {
    for (unsigned int u = 0; u < w; ++u) {
      const unsigned char g = I[v][u];
      canvas[v][u] = vpRGBa(g, g, g);
    }
  }
  if (slam.getState() == vpHSlam::stateTracking) {
    drawPoints(slam, canvas);
    drawWorldFrame(slam, canvas);
  }
  // Empty in direct mode and for a frame not tracked; drawn over the points, whose markers they may share.
  const std::vector<vpImagePoint> matches = slam.getDescriptorMatches();
  drawDescriptorMatches(matches, canvas, w, h);

  const vpHSlam::Statistics s = slam.getStatistics();
  std::ostringstream status;
  status << "frame " << frameIndex << "  " << vpHSlam::stateName(slam.getState());
  if (fps > 0.) {
    status << "  " << std::fixed << std::setprecision(1) << fps << " fps";
  }
  status << "  pts " << s.activePoints << "  kf " << s.keyframes;
  fill(canvas, 0, 0, w, kStatusBand, vpColor(0, 0, 0));
  // The status line in three pieces: its matches legend is written in the colour of their crosses.
  const vpColor statusColour = slam.getState() == vpHSlam::stateLost ? kCameraColour : kTextColour;
  vpImagePoint position(3, 6);
  auto write = [&](const std::string &text, const vpColor &colour) {
    font().drawText(canvas, text, position, colour);
    position.set_j(position.get_j() + font().getMeasure(text).get_j());
  };
  write(status.str(), statusColour);
  const vpHSlamParameters::TrackingMode mode = slam.getParameters().tracking.mode;
  if (mode == vpHSlamParameters::trackingAdaptive && matches.empty()) {
    write("  direct", statusColour); // adaptive tracking kept the photometric pose alone for this frame
  } else if (mode != vpHSlamParameters::trackingDirect) {
    write("  + orb " + std::to_string(matches.size()), kMatchColour); // the geometric term was used
  }
  if (slam.getTag().isSet()) {
    // Metres once the tag's fit is trusted (the tag drawn where the system places it), else how far it is.
    write(slam.isMetric() ? "  metric" : "  tag " + std::to_string(s.tagSightings), kTagColour);
  }
  if (!hint.empty()) {
    write("  " + hint, statusColour);
  }
  if (m_topViewWidth > 0) {
    drawTopView(slam, canvas, w, m_topViewWidth);
  }
}
