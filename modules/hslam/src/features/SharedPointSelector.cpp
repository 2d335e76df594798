/*
 * H-SLAM for ViSP.
 */
#include "features/SharedPointSelector.h"

#include "features/CornerDetector.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
SharedPointSelector::SharedPointSelector(const vpHSlamParameters::Features &params, bool withDescriptors)
    : m_params(params), m_withDescriptors(withDescriptors), m_gradients(params)
{
}

void SharedPointSelector::select(const vpImage<unsigned char> &raw, const ImagePyramid &pyramid, int desiredCount,
                                 unsigned int seed, std::vector<SelectedPixel> &selected, std::vector<bool> &isCorner,
                                 Kinds kinds)
{
  selected.clear();
  isCorner.clear();
  m_lastCorners = 0;
  if (!m_withDescriptors || kinds == gradientsOnly || m_params.maxCorners <= 0) {
    if (kinds == cornersOnly) {
      return;
    }
    m_gradients.select(pyramid, desiredCount, seed, selected);
    isCorner.assign(selected.size(), false);
    return;
  }
  CornerOptions options;
  options.threshold = m_params.fastThreshold;
  options.maxCorners =
      std::min(m_params.maxCorners, static_cast<int>(std::floor(m_params.cornerShare * std::max(0, desiredCount))));
  options.minDistance = m_params.cornerMinDistance;
  options.border = kOrbBorderPx + 1; // every corner gets a descriptor
  detectCorners(raw, options, m_corners, nullptr, &m_cornerHint);
  const int width = pyramid.level(0).width;
  selected.reserve(static_cast<size_t>(desiredCount) + m_corners.size());
  for (const cv::Point2f &c : m_corners) {
    SelectedPixel px;
    px.u = static_cast<int>(std::lround(c.x));
    px.v = static_cast<int>(std::lround(c.y));
    px.level = 0;
    selected.push_back(px);
  }
  m_lastCorners = static_cast<int>(m_corners.size());
  isCorner.assign(selected.size(), true);
  if (kinds == cornersOnly) {
    return;
  }
  // The gradient selector keeps its whole budget (corners come on top): taking cells away from it cost accuracy
  // (see the file comment). A gradient pixel on a corner's own pixel is dropped (the point exists already).
  m_gradients.select(pyramid, desiredCount, seed, m_gradientPixels);
  m_cornerPixels.clear();
  for (const SelectedPixel &c : selected) {
    m_cornerPixels.insert(static_cast<long long>(c.v) * width + c.u);
  }
  for (const SelectedPixel &px : m_gradientPixels) {
    if (m_cornerPixels.count(static_cast<long long>(px.v) * width + px.u) == 0) {
      selected.push_back(px);
    }
  }
  isCorner.resize(selected.size(), false);
}

void SharedPointSelector::describe(const vpImage<unsigned char> &raw, const std::vector<cv::Point2f> &pixels,
                                   std::vector<OrbDescriptor> &descriptors, std::vector<bool> &valid,
                                   std::vector<float> &anglesDeg)
{
  if (!m_withDescriptors) {
    descriptors.assign(pixels.size(), OrbDescriptor());
    valid.assign(pixels.size(), false);
    anglesDeg.assign(pixels.size(), 0.f);
    return;
  }
  m_descriptors.compute(raw, pixels, descriptors, valid, &anglesDeg);
}
} // namespace hslam
