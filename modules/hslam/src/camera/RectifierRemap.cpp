#include "camera/RectifierRemap.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace hslam
{

void RectifierRemap::build(unsigned int targetWidth, unsigned int targetHeight, unsigned int sourceWidth,
                           unsigned int sourceHeight, const SourceOf &sourceOf)
{
  if (targetWidth < 2 || targetHeight < 2 || sourceWidth < 2 || sourceHeight < 2) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ": remap needs images of at least 2x2 pixels (target " +
                               std::to_string(targetWidth) + "x" + std::to_string(targetHeight) + ", source " +
                               std::to_string(sourceWidth) + "x" + std::to_string(sourceHeight) + ")");
  }
  m_targetWidth = targetWidth;
  m_targetHeight = targetHeight;
  m_sourceWidth = sourceWidth;
  m_sourceHeight = sourceHeight;
  const std::size_t n = static_cast<std::size_t>(targetWidth) * targetHeight;
  m_sourceIndex.assign(n, 0);
  m_fracU.assign(n, 0);
  m_fracV.assign(n, 0);
  m_invalid.clear();

  const double lastColumn = sourceWidth - 2.0, lastRow = sourceHeight - 2.0;
  std::size_t k = 0;
  for (unsigned int y = 0; y < targetHeight; ++y) {
    for (unsigned int x = 0; x < targetWidth; ++x, ++k) {
      double u = 0.0, v = 0.0;
      if (!sourceOf(x, y, u, v) || !(u >= 0.0 && u <= sourceWidth - 1.0 && v >= 0.0 && v <= sourceHeight - 1.0)) {
        m_invalid.push_back(static_cast<uint32_t>(k));
        continue;
      }
      // Top-left corner of the 2x2 neighbourhood, kept one pixel inside the last row / column.
      const double u0 = std::min(std::floor(u), lastColumn);
      const double v0 = std::min(std::floor(v), lastRow);
      m_sourceIndex[k] = static_cast<int32_t>(v0) * static_cast<int32_t>(sourceWidth) + static_cast<int32_t>(u0);
      m_fracU[k] = static_cast<uint16_t>(std::lround((u - u0) * kFractionOne));
      m_fracV[k] = static_cast<uint16_t>(std::lround((v - v0) * kFractionOne));
    }
  }
}

void RectifierRemap::apply(const unsigned char *__restrict source, unsigned char *__restrict target) const
{
  const int32_t *__restrict index = m_sourceIndex.data();
  const uint16_t *__restrict fracU = m_fracU.data();
  const uint16_t *__restrict fracV = m_fracV.data();
  const std::size_t stride = m_sourceWidth;
  const std::size_t n = m_sourceIndex.size();
  constexpr int32_t kRound = 1 << (2 * kFractionBits - 1);
  for (std::size_t k = 0; k < n; ++k) {
    const unsigned char *p = source + index[k];
    const int32_t a = fracU[k], b = fracV[k];
    const int32_t p00 = p[0], p01 = p[1], p10 = p[stride], p11 = p[stride + 1];
    // Two horizontal lerps then one vertical lerp, all in fixed point (values scaled by 2^11, then 2^22).
    const int32_t top = (p00 << kFractionBits) + (p01 - p00) * a;
    const int32_t bottom = (p10 << kFractionBits) + (p11 - p10) * a;
    const int32_t value = (top << kFractionBits) + (bottom - top) * b;
    target[k] = static_cast<unsigned char>((value + kRound) >> (2 * kFractionBits));
  }
  for (const uint32_t k : m_invalid) {
    target[k] = kInvalidValue;
  }
}

void RectifierRemap::apply(const float *__restrict source, float *__restrict target) const
{
  const int32_t *__restrict index = m_sourceIndex.data();
  const uint16_t *__restrict fracU = m_fracU.data();
  const uint16_t *__restrict fracV = m_fracV.data();
  const std::size_t stride = m_sourceWidth;
  const std::size_t n = m_sourceIndex.size();
  constexpr float kScale = 1.0f / kFractionOne;
  for (std::size_t k = 0; k < n; ++k) {
    const float *p = source + index[k];
    const float a = fracU[k] * kScale, b = fracV[k] * kScale;
    const float top = p[0] + (p[1] - p[0]) * a;
    const float bottom = p[stride] + (p[stride + 1] - p[stride]) * a;
    target[k] = top + (bottom - top) * b;
  }
  for (const uint32_t k : m_invalid) {
    target[k] = static_cast<float>(kInvalidValue);
  }
}

} // namespace hslam
