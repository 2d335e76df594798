/*
 * H-SLAM for ViSP.
 */
/*!
  \file ImagePyramid.h
  \brief Image pyramid of a rectified frame with per-pixel intensity and gradients, as the direct part reads it.

  Layout (DSO's "dI"): each level stores, per pixel, (I, dI/du, dI/dv) contiguously as Eigen::Vector3f so one
  bilinear lookup gives the intensity and its gradient for the photometric Jacobians; a separate squared gradient
  norm is kept for pixel selection. Intensities are irradiance (photometrically corrected) or raw 8-bit values
  as floats when no calibration exists.

  Pixel convention: centre of the top-left pixel is (0, 0) at every level. Level l halves level l-1 by averaging
  2x2 blocks, so a level-0 coordinate x maps to (x + 0.5) / 2^l - 0.5 at level l, and the intrinsics follow:
  f_l = f_0 / 2^l, c_l = (c_0 + 0.5) / 2^l - 0.5.

  Ownership and threading: built once per frame by the tracking thread, then immutable and shared (read-only) by
  mapping through std::shared_ptr. build() reuses its buffers when the size does not change.
*/
#ifndef HSLAM_FEATURES_IMAGE_PYRAMID_H
#define HSLAM_FEATURES_IMAGE_PYRAMID_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <Eigen/Core>
#include <Eigen/StdVector>

#include <vector>

namespace hslam
{
//! Image width at which pixel thresholds are given (globalMap.reuseRadiusPx, mapper.rotationFlowPx); other widths
//! scale them.
constexpr double kReferenceWidthPx = 640.;

//! Pinhole intrinsics of one pyramid level, pixels.
struct PinholeIntrinsics {
  double fx = 1., fy = 1., cx = 0., cy = 0.;
  //! Intrinsics of the level below (half resolution), following the pixel-centre convention above.
  PinholeIntrinsics halved() const { return {fx * 0.5, fy * 0.5, (cx + 0.5) * 0.5 - 0.5, (cy + 0.5) * 0.5 - 0.5}; }
  //! The point at pixel (u, v) with inverse depth \e idepth, in this camera's frame.
  Eigen::Vector3d unproject(double u, double v, double idepth) const
  {
    return Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.) / idepth;
  }
  //! The pixel of point \e X of this camera's frame (its depth X.z() must be positive).
  Eigen::Vector2d project(const Eigen::Vector3d &X) const
  {
    return Eigen::Vector2d(fx * X.x() / X.z() + cx, fy * X.y() / X.z() + cy);
  }
};

//! One level: (I, dI/du, dI/dv) per pixel, row-major, plus squared gradient norm.
struct PyramidLevel {
  int width = 0;
  int height = 0;
  PinholeIntrinsics K;
  std::vector<Eigen::Vector3f, Eigen::aligned_allocator<Eigen::Vector3f>> color; //!< (I, dx, dy) per pixel
  std::vector<float> gradSq;                                                     //!< dx^2 + dy^2 per pixel

  //! True when (u, v) has room for bilinear interpolation and a border of \e margin pixels.
  bool isInside(float u, float v, float margin) const
  {
    return u >= margin && v >= margin && u < static_cast<float>(width) - 1.f - margin &&
           v < static_cast<float>(height) - 1.f - margin;
  }

  //! Bilinear (I, dx, dy) at (u, v); the caller guarantees isInside(u, v, 0).
  Eigen::Vector3f interpolate(float u, float v) const
  {
    const int iu = static_cast<int>(u);
    const int iv = static_cast<int>(v);
    const float du = u - static_cast<float>(iu);
    const float dv = v - static_cast<float>(iv);
    const Eigen::Vector3f *p = &color[static_cast<size_t>(iv * width + iu)];
    return (1.f - dv) * ((1.f - du) * p[0] + du * p[1]) + dv * ((1.f - du) * p[width] + du * p[width + 1]);
  }

  //! Ask the cache for the four pixels interpolate(u, v) reads (a hint: no effect on any result).
  void prefetch(float u, float v) const
  {
    const Eigen::Vector3f *p = &color[static_cast<size_t>(static_cast<int>(v) * width + static_cast<int>(u))];
    __builtin_prefetch(p);
    __builtin_prefetch(reinterpret_cast<const char *>(p + 2) - 1);
    __builtin_prefetch(p + width);
    __builtin_prefetch(reinterpret_cast<const char *>(p + width + 2) - 1);
  }

  //! Bilinear intensity only.
  float interpolateIntensity(float u, float v) const
  {
    const int iu = static_cast<int>(u);
    const int iv = static_cast<int>(v);
    const float du = u - static_cast<float>(iu);
    const float dv = v - static_cast<float>(iv);
    const Eigen::Vector3f *p = &color[static_cast<size_t>(iv * width + iu)];
    return (1.f - dv) * ((1.f - du) * p[0][0] + du * p[1][0]) + dv * ((1.f - du) * p[width][0] + du * p[width + 1][0]);
  }
};

/*!
  Standard deviation of the additive noise of an image level, in intensity units (Immerkaer, "Fast noise variance
  estimation", CVIU 1996): the mean absolute response to the Laplacian difference of two Laplacians
  [1 -2 1; -2 4 -2; 1 -2 1], which cancels smooth structure, times sqrt(pi / 2) / 6. Texture still adds a little, so
  on a sharp textured image this over-estimates a clean sensor's noise. 0 for a level smaller than 3x3.
*/
VISP_EXPORT double estimateNoiseSigma(const PyramidLevel &level);

/*!
  Pyramid of a rectified frame.

  Number of levels (DSO, setGlobalCalib): starting from level 0, a coarser level is added while the current
  coarsest level has MORE than \e minCoarsestPixels pixels, up to \e maxLevels levels. With DSO's 5000 this gives
  640x480 -> 4 levels (coarsest 80x60), 752x480 -> 5 (47x30), 1226x370 -> 5 (76x23).

  Odd sizes: DSO requires every level size to be even; we accept any size and use floor division, so level l+1
  has floor(w_l / 2) x floor(h_l / 2) pixels and drops the last column (row) of an odd-sized level. The retained
  pixels keep the exact relation x_{l+1} = (x_l + 0.5) / 2 - 0.5, so PinholeIntrinsics::halved() stays exact.
  A level must keep at least 2x2 pixels; no level is added below that.

  Gradients: central differences (I[x+1] - I[x-1]) / 2 inside, one-sided differences I[1] - I[0] (resp.
  I[w-1] - I[w-2]) on the first and last column (row), so a linear ramp has its exact slope everywhere.
*/
class VISP_EXPORT ImagePyramid
{
public:
  /*!
    Build from an intensity image (float, rectified) and the level-0 intrinsics. Buffers are reused: building
    a pyramid of the same size again allocates nothing.
    \param I : intensities of the rectified frame (irradiance or 8-bit values as float).
    \param K0 : level-0 pinhole intrinsics.
    \param maxLevels : upper bound on the number of levels (>= 1).
    \param minCoarsestPixels : a coarser level is added only while the current coarsest level has more than this
    many pixels (DSO: 5000, vpHSlamParameters::Tracker::minCoarsestPixels).
    \exception vpHSlamException::invalidImage on an empty image, invalidArgument when maxLevels < 1.
  */
  void build(const vpImage<float> &I, const PinholeIntrinsics &K0, int maxLevels, int minCoarsestPixels);
  //! Same from an 8-bit image (grey levels as floats), without an intermediate float image.
  void build(const vpImage<unsigned char> &I, const PinholeIntrinsics &K0, int maxLevels, int minCoarsestPixels);

  //! Number of levels DSO's rule gives for a width x height level 0 (see the class comment).
  static int levelCount(int width, int height, int maxLevels, int minCoarsestPixels);

  int numLevels() const { return m_numLevels; }
  const PyramidLevel &level(int l) const { return m_levels[static_cast<size_t>(l)]; }

private:
  template <typename T>
  void buildFrom(const vpImage<T> &I, const PinholeIntrinsics &K0, int maxLevels, int minCoarsestPixels);
  //! Sizes the levels (reusing their buffers), sets sizes and intrinsics.
  void prepareLevels(int width, int height, const PinholeIntrinsics &K0, int maxLevels, int minCoarsestPixels);

  std::vector<PyramidLevel> m_levels; //!< never shrinks, so buffers survive a call with fewer levels
  int m_numLevels = 0;
};
} // namespace hslam

#endif
