// vpHSlamTrajectoryEvaluator::drawTopView: a top-view picture of two trajectories.
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <visp3/core/vpColor.h>
#include <visp3/core/vpFont.h>
#include <visp3/core/vpImageDraw.h>
#include <visp3/core/vpImagePoint.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

namespace
{
constexpr unsigned int kMarginPixels = 60; //!< free border around the plot area
constexpr unsigned int kFontHeight = 18;   //!< legend and caption text, pixels
constexpr unsigned int kLineThickness = 2; //!< trajectory lines, pixels
constexpr unsigned int kStartMarkerRadius = 6;
constexpr double kTargetGridLines = 8.; //!< grid step chosen to give about this many lines across
constexpr unsigned int kLegendLineLength = 40;

const vpColor kBackground(255, 255, 255);
const vpColor kGridColour(225, 225, 225);
const vpColor kTextColour(20, 20, 20);
const vpColor kGroundTruthColour(0, 150, 0);
const vpColor kEstimateColour(220, 30, 30);

//! 1, 2 or 5 times a power of ten, at least \e raw: grid spacings people read at a glance.
double niceStep(double raw)
{
  const double power = std::pow(10., std::floor(std::log10(raw)));
  const double mantissa = raw / power;
  const double nice = mantissa <= 1. ? 1. : (mantissa <= 2. ? 2. : (mantissa <= 5. ? 5. : 10.));
  return nice * power;
}

std::vector<Eigen::Vector3d> positionsOf(const vpHSlamTrajectory &trajectory)
{
  std::vector<Eigen::Vector3d> p;
  p.reserve(trajectory.size());
  for (const vpHomogeneousMatrix &wMc : trajectory.getPoses()) {
    p.emplace_back(wMc[0][3], wMc[1][3], wMc[2][3]);
  }
  return p;
}

std::unique_ptr<vpFont> makeFont()
{
  // ViSP's built-in bitmap font. Not the TrueType default: in ViSP 3.5 (Debian) vpFont's TrueType path corrupts
  // memory on ordinary strings (e.g. "ground" crashes in vpFont::Impl::Draw); the bitmap path is clean under
  // valgrind, even for text crossing the image border.
  return std::unique_ptr<vpFont>(new vpFont(kFontHeight, vpFont::GENERIC_MONOSPACE));
}
} // namespace

namespace
{
//! The plane of largest spread of a trajectory (its principal axes): a top view for ground vehicles and drones
//! whatever the dataset's "up" axis is.
struct PrincipalPlane {
  Eigen::Vector3d centroid, axisU, axisV;
  Eigen::Vector2d project(const Eigen::Vector3d &p) const
  {
    return Eigen::Vector2d(axisU.dot(p - centroid), axisV.dot(p - centroid));
  }
};

PrincipalPlane principalPlane(const std::vector<Eigen::Vector3d> &reference)
{
  PrincipalPlane plane;
  plane.centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d &p : reference) {
    plane.centroid += p;
  }
  plane.centroid /= static_cast<double>(reference.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d &p : reference) {
    covariance += (p - plane.centroid) * (p - plane.centroid).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  plane.axisU = eigen.eigenvectors().col(2); // eigenvalues ascending: largest last
  // Eigenvector signs are arbitrary: orient the main axis so the trajectory runs from left to right.
  if (plane.axisU.dot(reference.back() - reference.front()) < 0.) {
    plane.axisU = -plane.axisU;
  }
  plane.axisV = eigen.eigenvectors().col(1);
  return plane;
}

//! Plane coordinates to image pixels: equal axes, the projected trajectories centred in the plot area.
struct PlotScale {
  Eigen::Vector2d mid, extent;
  double pixelsPerUnit;
  unsigned int width, height;
  vpImagePoint toPixel(const Eigen::Vector2d &q) const
  {
    // Image rows grow downwards: flip v so the picture is not mirrored.
    return vpImagePoint(0.5 * height - (q.y() - mid.y()) * pixelsPerUnit,
                        0.5 * width + (q.x() - mid.x()) * pixelsPerUnit);
  }
};

PlotScale fitPlot(const PrincipalPlane &plane, const std::vector<Eigen::Vector3d> &gt,
                  const std::vector<Eigen::Vector3d> &est, unsigned int width, unsigned int height)
{
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector2d hi = -lo;
  for (const std::vector<Eigen::Vector3d> *list : {&gt, &est}) {
    for (const Eigen::Vector3d &p : *list) {
      const Eigen::Vector2d q = plane.project(p);
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  }
  PlotScale plot;
  plot.extent = (hi - lo).cwiseMax(1e-6);
  const double plotW = width - 2. * kMarginPixels;
  const double plotH = height - 2. * kMarginPixels;
  plot.pixelsPerUnit = std::min(plotW / plot.extent.x(), plotH / plot.extent.y()); // equal axes
  plot.mid = 0.5 * (lo + hi);
  plot.width = width;
  plot.height = height;
  return plot;
}

//! Grid lines across the whole image, aligned with the projected origin (the ground-truth centroid); the step.
double drawGrid(vpImage<vpRGBa> &I, const PlotScale &plot)
{
  const double step = niceStep(std::max(plot.extent.x(), plot.extent.y()) / kTargetGridLines);
  const Eigen::Vector2d &mid = plot.mid;
  const double uMin = mid.x() - 0.5 * plot.width / plot.pixelsPerUnit;
  const double uMax = mid.x() + 0.5 * plot.width / plot.pixelsPerUnit;
  const double vMin = mid.y() - 0.5 * plot.height / plot.pixelsPerUnit;
  const double vMax = mid.y() + 0.5 * plot.height / plot.pixelsPerUnit;
  for (double u = std::ceil(uMin / step) * step; u <= uMax; u += step) {
    vpImageDraw::drawLine(I, plot.toPixel(Eigen::Vector2d(u, vMin)), plot.toPixel(Eigen::Vector2d(u, vMax)),
                          kGridColour, 1);
  }
  for (double v = std::ceil(vMin / step) * step; v <= vMax; v += step) {
    vpImageDraw::drawLine(I, plot.toPixel(Eigen::Vector2d(uMin, v)), plot.toPixel(Eigen::Vector2d(uMax, v)),
                          kGridColour, 1);
  }
  return step;
}

//! A trajectory as a polyline, its start circled.
void drawPath(vpImage<vpRGBa> &I, const PrincipalPlane &plane, const PlotScale &plot,
              const std::vector<Eigen::Vector3d> &list, const vpColor &colour)
{
  for (size_t i = 1; i < list.size(); ++i) {
    vpImageDraw::drawLine(I, plot.toPixel(plane.project(list[i - 1])), plot.toPixel(plane.project(list[i])), colour,
                          kLineThickness);
  }
  if (!list.empty()) {
    vpImageDraw::drawCircle(I, plot.toPixel(plane.project(list.front())), kStartMarkerRadius, colour, kLineThickness);
  }
}

//! Caption (top left), legend and grid spacing (bottom left).
void drawLegend(vpImage<vpRGBa> &I, const std::string &caption, double step, unsigned int height)
{
  std::unique_ptr<vpFont> font = makeFont();
  const double lineGap = 1.5 * kFontHeight;
  const double left = 0.5 * kMarginPixels;
  double row = 0.5 * kMarginPixels;
  if (!caption.empty()) {
    font->drawText(I, caption, vpImagePoint(row - 0.5 * kFontHeight, left), kTextColour);
  }
  row = height - 0.5 * kMarginPixels - 2. * lineGap;
  const struct {
    const char *label;
    vpColor colour;
  } legend[] = {{"ground truth", kGroundTruthColour}, {"estimate (aligned)", kEstimateColour}};
  for (const auto &entry : legend) {
    vpImageDraw::drawLine(I, vpImagePoint(row, left), vpImagePoint(row, left + kLegendLineLength), entry.colour,
                          kLineThickness + 1);
    font->drawText(I, entry.label, vpImagePoint(row - 0.6 * kFontHeight, left + kLegendLineLength + 10), kTextColour);
    row += lineGap;
  }
  char text[128];
  std::snprintf(text, sizeof(text), "grid %g m, circles = start", step);
  font->drawText(I, text, vpImagePoint(row - 0.6 * kFontHeight, left), kTextColour);
}
} // namespace

void vpHSlamTrajectoryEvaluator::drawTopView(vpImage<vpRGBa> &I, const vpHSlamTrajectory &groundTruth,
                                             const vpHSlamTrajectory &estimate, const std::string &caption,
                                             unsigned int width, unsigned int height)
{
  if (width <= 2 * kMarginPixels || height <= 2 * kMarginPixels) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "drawTopView: image too small");
  }
  I.resize(height, width, vpRGBa(kBackground.R, kBackground.G, kBackground.B));
  const std::vector<Eigen::Vector3d> gt = positionsOf(groundTruth);
  const std::vector<Eigen::Vector3d> est = positionsOf(estimate);
  const std::vector<Eigen::Vector3d> &reference = gt.empty() ? est : gt;
  if (reference.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "drawTopView: both trajectories are empty");
  }
  // The picture shows the plane of largest spread of the ground truth (of the estimate when there is none).
  const PrincipalPlane plane = principalPlane(reference);
  const PlotScale plot = fitPlot(plane, gt, est, width, height);
  const double step = drawGrid(I, plot);
  drawPath(I, plane, plot, gt, kGroundTruthColour);
  drawPath(I, plane, plot, est, kEstimateColour);
  drawLegend(I, caption, step, height);
}
