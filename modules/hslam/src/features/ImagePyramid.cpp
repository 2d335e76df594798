/*
 * H-SLAM for ViSP.
 */
// Image pyramid: level 0 copied from the input, coarser levels by 2x2 means, gradients by central differences
// (DSO FrameHessian::makeImages), level count by DSO's pixel-count rule (see ImagePyramid.h).
#include "features/ImagePyramid.h"

#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
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

//! o[3x..3x+2] = (a[x], b[x], c[x]) for x < n: the (I, dx, dy) layout of PyramidLevel::color.
void interleave(const float *__restrict a, const float *__restrict b, const float *__restrict c, int n,
                float *__restrict o)
{
  int x = 0;
#ifdef __SSE2__
  // Four pixels per step: 12 floats written as three 16-byte stores (the compiler leaves this loop scalar).
  for (; x + 4 <= n; x += 4) {
    const __m128 va = _mm_loadu_ps(a + x); // a0 a1 a2 a3
    const __m128 vb = _mm_loadu_ps(b + x);
    const __m128 vc = _mm_loadu_ps(c + x);
    // _mm_shuffle_ps(x, y, _MM_SHUFFLE(d, c, b, a)) = (x[a], x[b], y[c], y[d]).
    const __m128 ab01 = _mm_unpacklo_ps(va, vb);                         // a0 b0 a1 b1
    const __m128 ab23 = _mm_unpackhi_ps(va, vb);                         // a2 b2 a3 b3
    const __m128 c0a1 = _mm_shuffle_ps(vc, va, _MM_SHUFFLE(1, 1, 0, 0)); // c0 c0 a1 a1
    const __m128 b1c1 = _mm_shuffle_ps(vb, vc, _MM_SHUFFLE(1, 1, 1, 1)); // b1 b1 c1 c1
    const __m128 c2a3 = _mm_shuffle_ps(vc, va, _MM_SHUFFLE(3, 3, 2, 2)); // c2 c2 a3 a3
    const __m128 b3c3 = _mm_shuffle_ps(vb, vc, _MM_SHUFFLE(3, 3, 3, 3)); // b3 b3 c3 c3
    float *p = o + 3 * x;
    _mm_storeu_ps(p, _mm_shuffle_ps(ab01, c0a1, _MM_SHUFFLE(2, 0, 1, 0)));     // a0 b0 c0 a1
    _mm_storeu_ps(p + 4, _mm_shuffle_ps(b1c1, ab23, _MM_SHUFFLE(1, 0, 2, 0))); // b1 c1 a2 b2
    _mm_storeu_ps(p + 8, _mm_shuffle_ps(c2a3, b3c3, _MM_SHUFFLE(2, 0, 2, 0))); // c2 a3 b3 c3
  }
#endif
  for (; x < n; ++x) {
    o[3 * x] = a[x];
    o[3 * x + 1] = b[x];
    o[3 * x + 2] = c[x];
  }
}

/*!
  Fills a level in one pass over its rows: intensities (loadRow(y, out) writes the w intensities of row y into a
  ring of three contiguous rows, rows loaded in order), central-difference gradients (dx, dy) and gradSq,
  interleaved into level.color. When coarse is not null, the next level's intensities (2x2 means, floor division
  of the size) are written there, contiguous, while the rows they need are in the ring. The level (3.7 MB at
  640x480) is written once and never read back from memory; the next level reads a contiguous plane instead of
  strided pixels. The arithmetic per pixel is the same as separate copy, gradient and downsampling passes.
*/
template <typename RowLoader>
void fillLevel(PyramidLevel &level, std::vector<float> &scratch, RowLoader loadRow, float *coarse)
{
  const int w = level.width;
  const int h = level.height;
  const int wc = w / 2;
  const int hc = h / 2;
  // Three intensity rows (a ring indexed by y % 3), then one row of dx and one of dy.
  scratch.resize(5 * static_cast<size_t>(w));
  const auto slot = [&scratch, w](int y) { return scratch.data() + static_cast<ptrdiff_t>(y % 3) * w; };
  float *__restrict dxRow = scratch.data() + 3 * static_cast<ptrdiff_t>(w);
  float *__restrict dyRow = dxRow + w;
  const auto load = [&](int y) {
    loadRow(y, slot(y));
    if (coarse != nullptr && y % 2 == 1 && y / 2 < hc) {
      const float *__restrict r0 = slot(y - 1);
      const float *__restrict r1 = slot(y);
      float *__restrict c = coarse + static_cast<ptrdiff_t>(y / 2) * wc;
      for (int x = 0; x < wc; ++x) {
        c[x] = kQuarter * (r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1]);
      }
    }
  };
  load(0);
  load(1);
  float *out = level.color.data()->data(); // Vector3f is three packed floats: (I, dx, dy) per pixel
  for (int y = 0; y < h; ++y) {
    if (y >= 1 && y + 1 < h) {
      load(y + 1);
    }
    // One-sided differences on the first and last row (step 1 instead of 2, hence scale 1).
    const int yUp = y > 0 ? y - 1 : y;
    const int yDown = y < h - 1 ? y + 1 : y;
    const float scaleY = (yDown - yUp) == 2 ? kCentralDifferenceScale : 1.f;
    const float *__restrict up = slot(yUp);
    const float *__restrict mid = slot(y);
    const float *__restrict down = slot(yDown);
    float *__restrict g = level.gradSq.data() + static_cast<ptrdiff_t>(y) * w;
    // Separate simple loops over contiguous rows: each one vectorises.
    dxRow[0] = mid[1] - mid[0]; // first and last column: one-sided
    for (int x = 1; x < w - 1; ++x) {
      dxRow[x] = kCentralDifferenceScale * (mid[x + 1] - mid[x - 1]);
    }
    dxRow[w - 1] = mid[w - 1] - mid[w - 2];
    for (int x = 0; x < w; ++x) {
      dyRow[x] = scaleY * (down[x] - up[x]);
      g[x] = dxRow[x] * dxRow[x] + dyRow[x] * dyRow[x];
    }
    interleave(mid, dxRow, dyRow, w, out + 3 * static_cast<ptrdiff_t>(y) * w);
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
  std::vector<float> scratch;
  // Intensities of the level being filled (input) and of the next one (output), contiguous.
  std::vector<float> planeIn, planeOut;
  const auto coarsePlane = [this, &planeOut](int l) -> float * {
    if (l + 1 >= m_numLevels) {
      return nullptr;
    }
    const PyramidLevel &next = m_levels[static_cast<size_t>(l + 1)];
    planeOut.resize(static_cast<size_t>(next.width) * static_cast<size_t>(next.height));
    return planeOut.data();
  };
  const T *src = I.bitmap;
  const int w0 = m_levels[0].width;
  fillLevel(
      m_levels[0], scratch,
      [src, w0](int y, float *row) {
        const T *in = src + static_cast<ptrdiff_t>(y) * w0;
        for (int x = 0; x < w0; ++x) {
          row[x] = static_cast<float>(in[x]);
        }
      },
      coarsePlane(0));
  for (int l = 1; l < m_numLevels; ++l) {
    planeIn.swap(planeOut);
    const int w = m_levels[static_cast<size_t>(l)].width;
    const float *in = planeIn.data();
    fillLevel(
        m_levels[static_cast<size_t>(l)], scratch,
        [in, w](int y, float *row) {
          std::copy(in + static_cast<ptrdiff_t>(y) * w, in + static_cast<ptrdiff_t>(y + 1) * w, row);
        },
        coarsePlane(l));
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
