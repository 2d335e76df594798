/*
 * H-SLAM for ViSP.
 */
#include "features/PointDescriptors.h"

#include <array>
#include <cmath>

namespace hslam
{
namespace
{
constexpr int kHalfPatch = 15; //!< radius of the orientation disc (ORB: patch 31)
constexpr int kPatchSize = 31; //!< rBRIEF patch
constexpr int kWtaK = 2;       //!< plain binary tests (Hamming distance)
constexpr float kRadToDeg = static_cast<float>(180.0 / M_PI);
} // namespace

PointDescriptors::PointDescriptors()
    : m_orb(cv::ORB::create(1, 1.2f, 1, kOrbBorderPx, 0, kWtaK, cv::ORB::HARRIS_SCORE, kPatchSize))
{
}

float PointDescriptors::orientation(const vpImage<unsigned char> &I, int u, int v)
{
  // Moments m10, m01 over the disc of radius 15 (rows of half-width floor(sqrt(r^2 - dv^2))), summed in integers
  // row by row (exact, so the same angles as a sum of doubles, three times faster).
  static const std::array<int, 2 *kHalfPatch + 1> halfWidths = [] {
    std::array<int, 2 * kHalfPatch + 1> w{};
    for (int dv = -kHalfPatch; dv <= kHalfPatch; ++dv) {
      w[static_cast<size_t>(dv + kHalfPatch)] =
          static_cast<int>(std::floor(std::sqrt(static_cast<double>(kHalfPatch * kHalfPatch - dv * dv))));
    }
    return w;
  }();
  long m10 = 0, m01 = 0;
  for (int dv = -kHalfPatch; dv <= kHalfPatch; ++dv) {
    const int halfWidth = halfWidths[static_cast<size_t>(dv + kHalfPatch)];
    const unsigned char *row = I[static_cast<unsigned int>(v + dv)] + u;
    int rowSum = 0, rowMoment = 0;
    for (int du = -halfWidth; du <= halfWidth; ++du) {
      rowSum += row[du];
      rowMoment += du * row[du];
    }
    m10 += rowMoment;
    m01 += static_cast<long>(dv) * rowSum;
  }
  float angle = static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10))) * kRadToDeg;
  if (angle < 0.f) {
    angle += 360.f;
  }
  return angle >= 360.f ? 0.f : angle;
}

void PointDescriptors::compute(const vpImage<unsigned char> &I, const std::vector<cv::Point2f> &pixels,
                               std::vector<OrbDescriptor> &descriptors, std::vector<bool> &valid,
                               std::vector<float> *anglesDeg)
{
  descriptors.assign(pixels.size(), OrbDescriptor());
  valid.assign(pixels.size(), false);
  if (anglesDeg) {
    anglesDeg->assign(pixels.size(), 0.f);
  }
  const int w = static_cast<int>(I.getWidth()), h = static_cast<int>(I.getHeight());
  m_keypoints.clear();
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const int u = static_cast<int>(std::lround(pixels[i].x)), v = static_cast<int>(std::lround(pixels[i].y));
    // One pixel more than OpenCV's own border filter, so that it never drops a point we kept.
    if (u <= kOrbBorderPx || v <= kOrbBorderPx || u >= w - 1 - kOrbBorderPx || v >= h - 1 - kOrbBorderPx) {
      continue;
    }
    cv::KeyPoint kp(pixels[i], static_cast<float>(kPatchSize), orientation(I, u, v), 0.f, 0, static_cast<int>(i));
    if (anglesDeg) {
      (*anglesDeg)[i] = kp.angle;
    }
    m_keypoints.push_back(kp);
  }
  if (m_keypoints.empty()) {
    return;
  }
  const cv::Mat image(h, w, CV_8UC1, const_cast<unsigned char *>(I.bitmap));
  cv::Mat rows;
  m_orb->compute(image, m_keypoints, rows);
  // compute() may reorder or drop keypoints: class_id carries each one's index.
  for (int r = 0; r < rows.rows && r < static_cast<int>(m_keypoints.size()); ++r) {
    const std::size_t index = static_cast<std::size_t>(m_keypoints[static_cast<std::size_t>(r)].class_id);
    descriptors[index] = descriptorFromBytes(rows.ptr<std::uint8_t>(r));
    valid[index] = true;
  }
}
} // namespace hslam
