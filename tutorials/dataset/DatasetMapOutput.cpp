// See DatasetMapOutput.h.
#include "dataset/DatasetMapOutput.h"

#include <visp3/core/vpImageDraw.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageIo.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace hslam_dataset
{
namespace
{
constexpr unsigned int kPngWidth = 1000, kPngHeight = 800, kMarginPx = 30;
//! A point is a square of this side, pixels.
constexpr int kPointPx = 2;
//! Points farther from the trajectory's centre than this many times its extent do not widen the framing.
constexpr double kFramingExtents = 3.;
} // namespace

void writeMapPly(const std::string &path, const std::vector<vpHSlam::MapPoint> &points,
                 const std::vector<vpHSlam::Keyframe> &keyframes)
{
  std::ofstream out(path.c_str());
  if (!out) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot write the map file '" + path + "'");
  }
  out << "ply\nformat ascii 1.0\ncomment H-SLAM map: orange = active points, grey = global map, red = keyframes\n"
      << "element vertex " << points.size() + keyframes.size() << "\n"
      << "property float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  for (const vpHSlam::MapPoint &p : points) {
    out << p.wX[0] << ' ' << p.wX[1] << ' ' << p.wX[2] << (p.active ? " 255 140 0\n" : " 128 128 128\n");
  }
  for (const vpHSlam::Keyframe &k : keyframes) {
    out << k.wMc[0][3] << ' ' << k.wMc[1][3] << ' ' << k.wMc[2][3] << " 220 30 30\n";
  }
  if (!out) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "error while writing the map file '" + path + "'");
  }
}

void writeMapPng(const std::string &path, const std::vector<vpHSlam::MapPoint> &points,
                 const vpHSlamTrajectory &trajectory)
{
  if (trajectory.size() == 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "map picture: the run has no pose to draw");
  }
  std::vector<Eigen::Vector3d> path3;
  for (const vpHomogeneousMatrix &M : trajectory.getPoses()) {
    path3.emplace_back(M[0][3], M[1][3], M[2][3]);
  }
  // Projection plane: the two main directions of the camera path (a top view for cars and hand-held cameras).
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d &p : path3) {
    centre += p;
  }
  centre /= static_cast<double>(path3.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Identity() * 1e-12;
  for (const Eigen::Vector3d &p : path3) {
    C += (p - centre) * (p - centre).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  const Eigen::Vector3d ax = eig.eigenvectors().col(2), ay = eig.eigenvectors().col(1);
  auto plane = [&](const Eigen::Vector3d &p) { return Eigen::Vector2d(ax.dot(p - centre), ay.dot(p - centre)); };
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e300), hi = -lo;
  for (const Eigen::Vector3d &p : path3) {
    lo = lo.cwiseMin(plane(p));
    hi = hi.cwiseMax(plane(p));
  }
  const double pathExtent = std::max((hi - lo).maxCoeff(), 1e-3);
  for (const vpHSlam::MapPoint &m : points) {
    const Eigen::Vector2d q = plane(Eigen::Vector3d(m.wX[0], m.wX[1], m.wX[2]));
    if (q.norm() < kFramingExtents * pathExtent) {
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
  }
  const Eigen::Vector2d extent = (hi - lo).cwiseMax(1e-6);
  const double scale = std::min((kPngWidth - 2. * kMarginPx) / extent.x(), (kPngHeight - 2. * kMarginPx) / extent.y());
  const Eigen::Vector2d mid = 0.5 * (lo + hi);
  auto pixel = [&](const Eigen::Vector2d &q) {
    return vpImagePoint(0.5 * kPngHeight - (q.y() - mid.y()) * scale, 0.5 * kPngWidth + (q.x() - mid.x()) * scale);
  };
  vpImage<vpRGBa> I(kPngHeight, kPngWidth, vpRGBa(255, 255, 255));
  for (const vpHSlam::MapPoint &m : points) {
    const vpImagePoint ip = pixel(plane(Eigen::Vector3d(m.wX[0], m.wX[1], m.wX[2])));
    const int r0 = static_cast<int>(ip.get_i()), c0 = static_cast<int>(ip.get_j());
    for (int r = r0; r < r0 + kPointPx; ++r) {
      for (int c = c0; c < c0 + kPointPx; ++c) {
        if (r >= 0 && c >= 0 && r < static_cast<int>(kPngHeight) && c < static_cast<int>(kPngWidth)) {
          I[r][c] = m.active ? vpRGBa(255, 140, 0) : vpRGBa(110, 110, 110);
        }
      }
    }
  }
  for (size_t i = 1; i < path3.size(); ++i) {
    vpImageDraw::drawLine(I, pixel(plane(path3[i - 1])), pixel(plane(path3[i])), vpColor(220, 30, 30), 2);
  }
  vpImageDraw::drawCircle(I, pixel(plane(path3.front())), 6, vpColor(220, 30, 30), 2);
  try {
    vpHSlamImageIo::writePng(path, I);
  } catch (const vpException &e) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "cannot write the map picture '" + path + "': " + e.getStringMessage());
  }
}
} // namespace hslam_dataset
