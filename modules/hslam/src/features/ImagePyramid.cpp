/*
 * H-SLAM for ViSP.
 */
// Image pyramid: level 0 copied from the input, coarser levels by 2x2 means, gradients by central differences
// (DSO FrameHessian::makeImages), level count by DSO's pixel-count rule (see ImagePyramid.h).
#include "features/ImagePyramid.h"

#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cmath>
#include <sstream>

namespace hslam
{
namespace
{
//! Smallest side a level may have: bilinear interpolation and central differences need two pixels.
constexpr int kMinLevelSide = 2;
//! Central difference (I[x+1] - I[x-1]) / 2.
constexpr float kCentralDifferenceScale = 0.5f;
//! Mean of a 2x2 block.
constexpr float kQuarter = 0.25f;

[[noreturn]] void throwInvalid(vpHSlamException::ErrorCode code, int line, const std::string &what)
{
  throwAt(code, __FILE__, static_cast<std::size_t>(line), "ImagePyramid::build: " + what);
}

//! Fills (dx, dy) and gradSq of a level whose intensities are set.
void computeGradients(PyramidLevel &level)
{
  const int w = level.width;
  const int h = level.height;
  Eigen::Vector3f *color = level.color.data();
  float *gradSq = level.gradSq.data();
  for (int y = 0; y < h; ++y) {
    // One-sided differences on the first and last row (step 1 instead of 2, hence scale 1).
    const int yUp = y > 0 ? y - 1 : y;
    const int yDown = y < h - 1 ? y + 1 : y;
    const float scaleY = (yDown - yUp) == 2 ? kCentralDifferenceScale : 1.f;
    const Eigen::Vector3f *up = color + static_cast<ptrdiff_t>(yUp) * w;
    const Eigen::Vector3f *down = color + static_cast<ptrdiff_t>(yDown) * w;
    Eigen::Vector3f *row = color + static_cast<ptrdiff_t>(y) * w;
    float *gRow = gradSq + static_cast<ptrdiff_t>(y) * w;

    // First and last column: one-sided. (Two simple loops per row measured faster than one with border tests.)
    row[0][1] = row[1][0] - row[0][0];
    for (int x = 1; x < w - 1; ++x) {
      row[x][1] = kCentralDifferenceScale * (row[x + 1][0] - row[x - 1][0]);
    }
    row[w - 1][1] = row[w - 1][0] - row[w - 2][0];

    for (int x = 0; x < w; ++x) {
      const float dy = scaleY * (down[x][0] - up[x][0]);
      row[x][2] = dy;
      gRow[x] = row[x][1] * row[x][1] + dy * dy;
    }
  }
}

//! Level l+1 intensities as 2x2 means of level l (floor division of the size).
void downsample(const PyramidLevel &fine, PyramidLevel &coarse)
{
  const int wf = fine.width;
  for (int y = 0; y < coarse.height; ++y) {
    const Eigen::Vector3f *r0 = fine.color.data() + static_cast<ptrdiff_t>(2 * y) * wf;
    const Eigen::Vector3f *r1 = r0 + wf;
    Eigen::Vector3f *out = coarse.color.data() + static_cast<ptrdiff_t>(y) * coarse.width;
    for (int x = 0; x < coarse.width; ++x) {
      out[x][0] = kQuarter * (r0[2 * x][0] + r0[2 * x + 1][0] + r1[2 * x][0] + r1[2 * x + 1][0]);
    }
  }
}
} // namespace

double estimateNoiseSigma(const PyramidLevel &level)
{
  const int w = level.width;
  const int h = level.height;
  if (w < 3 || h < 3) {
    return 0.;
  }
  const auto at = [&level, w](int x, int y) { return level.color[static_cast<size_t>(y * w + x)][0]; };
  double sum = 0.;
  for (int y = 1; y < h - 1; ++y) {
    for (int x = 1; x < w - 1; ++x) {
      const float corners = at(x - 1, y - 1) + at(x + 1, y - 1) + at(x - 1, y + 1) + at(x + 1, y + 1);
      const float edges = at(x, y - 1) + at(x - 1, y) + at(x + 1, y) + at(x, y + 1);
      sum += std::fabs(static_cast<double>(corners - 2.f * edges + 4.f * at(x, y)));
    }
  }
  const double kPi = 3.14159265358979323846;
  return std::sqrt(kPi / 2.) / 6. * sum / (static_cast<double>(w - 2) * static_cast<double>(h - 2));
}

int ImagePyramid::levelCount(int width, int height, int maxLevels, int minCoarsestPixels)
{
  int levels = 1;
  int w = width;
  int h = height;
  // DSO: add a level while the current coarsest one has more than minCoarsestPixels pixels.
  while (levels<maxLevels &&static_cast<long long>(w) * h> minCoarsestPixels && w / 2 >= kMinLevelSide &&
         h / 2 >= kMinLevelSide) {
    w /= 2;
    h /= 2;
    ++levels;
  }
  return levels;
}

void ImagePyramid::prepareLevels(int width, int height, const PinholeIntrinsics &K0, int maxLevels,
                                 int minCoarsestPixels)
{
  if (width < kMinLevelSide || height < kMinLevelSide) {
    std::ostringstream os;
    os << "image of " << width << "x" << height << " pixels, at least " << kMinLevelSide << "x" << kMinLevelSide
       << " needed";
    throwInvalid(vpHSlamException::invalidImage, __LINE__, os.str());
  }
  if (maxLevels < 1) {
    throwInvalid(vpHSlamException::invalidArgument, __LINE__,
                 "maxLevels = " + std::to_string(maxLevels) + ", must be >= 1");
  }
  m_numLevels = levelCount(width, height, maxLevels, minCoarsestPixels);
  if (static_cast<int>(m_levels.size()) < m_numLevels) {
    m_levels.resize(static_cast<size_t>(m_numLevels));
  }
  int w = width;
  int h = height;
  PinholeIntrinsics K = K0;
  for (int l = 0; l < m_numLevels; ++l) {
    PyramidLevel &level = m_levels[static_cast<size_t>(l)];
    level.width = w;
    level.height = h;
    level.K = K;
    // resize() to the same size keeps the storage: no allocation for a repeated size.
    const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
    level.color.resize(n);
    level.gradSq.resize(n);
    w /= 2;
    h /= 2;
    K = K.halved();
  }
}

template <typename T>
void ImagePyramid::buildFrom(const vpImage<T> &I, const PinholeIntrinsics &K0, int maxLevels, int minCoarsestPixels)
{
  prepareLevels(static_cast<int>(I.getWidth()), static_cast<int>(I.getHeight()), K0, maxLevels, minCoarsestPixels);
  PyramidLevel &level0 = m_levels[0];
  const T *src = I.bitmap;
  const size_t n = level0.color.size();
  for (size_t i = 0; i < n; ++i) {
    level0.color[i][0] = static_cast<float>(src[i]);
  }
  computeGradients(level0);
  for (int l = 1; l < m_numLevels; ++l) {
    downsample(m_levels[static_cast<size_t>(l - 1)], m_levels[static_cast<size_t>(l)]);
    computeGradients(m_levels[static_cast<size_t>(l)]);
  }
}

void ImagePyramid::build(const vpImage<float> &I, const PinholeIntrinsics &K0, int maxLevels, int minCoarsestPixels)
{
  buildFrom(I, K0, maxLevels, minCoarsestPixels);
}

void ImagePyramid::build(const vpImage<unsigned char> &I, const PinholeIntrinsics &K0, int maxLevels,
                         int minCoarsestPixels)
{
  buildFrom(I, K0, maxLevels, minCoarsestPixels);
}
} // namespace hslam
