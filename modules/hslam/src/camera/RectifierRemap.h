/*
 * H-SLAM for ViSP.
 */
/*!
  \file RectifierRemap.h
  \brief Precomputed bilinear remap table (structure of arrays, fixed-point weights) and its per-frame application.
*/
#ifndef HSLAM_RECTIFIER_REMAP_H
#define HSLAM_RECTIFIER_REMAP_H

#include <visp3/core/vpConfig.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace hslam
{

/*!
  Remap table from a target image to a source image, built once and applied to every frame.

  Per target pixel k it stores, in three contiguous arrays, the index of the top-left source pixel of the bilinear
  neighbourhood and the horizontal / vertical fractions in fixed point (kFractionBits bits). The apply loops read
  the arrays sequentially, gather four source pixels and have no branch: a target pixel without a source points at
  source pixel 0 with zero fractions and is overwritten afterwards from a (usually empty) list of invalid pixels.
  Neighbourhoods touching the last row / column are shifted one pixel up / left with a fraction of one, so the
  four reads never leave the source image.

  Not thread-safe to build; apply() is const and may run concurrently on different outputs.
*/
class VISP_EXPORT RectifierRemap
{
public:
  //! Fixed-point precision of the bilinear fractions: 1/2048 px. 11 bits keep the 8-bit path in int32:
  //! 255 * 2^22 + rounding < 2^31.
  static constexpr int kFractionBits = 11;
  static constexpr int32_t kFractionOne = 1 << kFractionBits;
  //! Value written where the target pixel has no source (DSO also leaves such pixels black).
  static constexpr unsigned char kInvalidValue = 0;

  /*!
    Source position of a target pixel.
    \param x, y : target pixel.
    \param u, v : source pixel, inside [0, sourceWidth-1] x [0, sourceHeight-1].
    \return false when the target pixel has no source.
  */
  using SourceOf = std::function<bool(unsigned int x, unsigned int y, double &u, double &v)>;

  /*!
    Fill the table. Source and target must both be at least 2x2.
  */
  void build(unsigned int targetWidth, unsigned int targetHeight, unsigned int sourceWidth, unsigned int sourceHeight,
             const SourceOf &sourceOf);

  //! Remap an 8-bit image: \e source holds sourceWidth*sourceHeight pixels, \e target targetWidth*targetHeight.
  void apply(const unsigned char *source, unsigned char *target) const;
  //! Remap a float image (same table, fractions converted to float).
  void apply(const float *source, float *target) const;

  unsigned int targetWidth() const { return m_targetWidth; }
  unsigned int targetHeight() const { return m_targetHeight; }
  unsigned int sourceWidth() const { return m_sourceWidth; }
  unsigned int sourceHeight() const { return m_sourceHeight; }
  //! Row-major indices of target pixels that have no source.
  const std::vector<uint32_t> &invalidPixels() const { return m_invalid; }

private:
  unsigned int m_targetWidth = 0, m_targetHeight = 0;
  unsigned int m_sourceWidth = 0, m_sourceHeight = 0;
  std::vector<int32_t> m_sourceIndex; //!< top-left source pixel, row-major
  std::vector<uint16_t> m_fracU;      //!< horizontal fraction in [0, kFractionOne]
  std::vector<uint16_t> m_fracV;      //!< vertical fraction in [0, kFractionOne]
  std::vector<uint32_t> m_invalid;
};

} // namespace hslam

#endif
