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

  // Principal axes of the ground truth: the picture shows the plane of largest spread (a top view for ground
  // vehicles and drones whatever the dataset's "up" axis is).
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d &p : reference) {
    centroid += p;
  }
  centroid /= static_cast<double>(reference.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d &p : reference) {
    covariance += (p - centroid) * (p - centroid).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  Eigen::Vector3d axisU = eigen.eigenvectors().col(2); // eigenvalues ascending: largest last
  // Eigenvector signs are arbitrary: orient the main axis so the trajectory runs from left to right.
  if (axisU.dot(reference.back() - reference.front()) < 0.) {
    axisU = -axisU;
  }
  const Eigen::Vector3d axisV = eigen.eigenvectors().col(1);
  auto project = [&](const Eigen::Vector3d &p) {
    return Eigen::Vector2d(axisU.dot(p - centroid), axisV.dot(p - centroid));
  };

  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector2d hi = -lo;
  for (const std::vector<Eigen::Vector3d> *list : {&gt, &est}) {
    for (const Eigen::Vector3d &p : *list) {
      const Eigen::Vector2d q = project(p);
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  }
  const Eigen::Vector2d extent = (hi - lo).cwiseMax(1e-6);
  const double plotW = width - 2. * kMarginPixels;
  const double plotH = height - 2. * kMarginPixels;
  const double pixelsPerUnit = std::min(plotW / extent.x(), plotH / extent.y()); // equal axes
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  auto toPixel = [&](const Eigen::Vector2d &q) {
    // Image rows grow downwards: flip v so the picture is not mirrored.
    return vpImagePoint(0.5 * height - (q.y() - mid.y()) * pixelsPerUnit,
                        0.5 * width + (q.x() - mid.x()) * pixelsPerUnit);
  };

  // Grid, aligned with the projected origin (the ground-truth centroid).
  const double step = niceStep(std::max(extent.x(), extent.y()) / kTargetGridLines);
  const double uMin = mid.x() - 0.5 * width / pixelsPerUnit, uMax = mid.x() + 0.5 * width / pixelsPerUnit;
  const double vMin = mid.y() - 0.5 * height / pixelsPerUnit, vMax = mid.y() + 0.5 * height / pixelsPerUnit;
  for (double u = std::ceil(uMin / step) * step; u <= uMax; u += step) {
    vpImageDraw::drawLine(I, toPixel(Eigen::Vector2d(u, vMin)), toPixel(Eigen::Vector2d(u, vMax)), kGridColour, 1);
  }
  for (double v = std::ceil(vMin / step) * step; v <= vMax; v += step) {
    vpImageDraw::drawLine(I, toPixel(Eigen::Vector2d(uMin, v)), toPixel(Eigen::Vector2d(uMax, v)), kGridColour, 1);
  }

  auto drawPath = [&](const std::vector<Eigen::Vector3d> &list, const vpColor &colour) {
    for (size_t i = 1; i < list.size(); ++i) {
      vpImageDraw::drawLine(I, toPixel(project(list[i - 1])), toPixel(project(list[i])), colour, kLineThickness);
    }
    if (!list.empty()) {
      vpImageDraw::drawCircle(I, toPixel(project(list.front())), kStartMarkerRadius, colour, kLineThickness);
    }
  };
  drawPath(gt, kGroundTruthColour);
  drawPath(est, kEstimateColour);

  // Legend, grid spacing, caption.
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
