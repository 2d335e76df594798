/*
 * H-SLAM for ViSP.
 */
/*!
  \file PatchPattern.h
  \brief The 8-pixel residual pattern of the direct part (DSO's default pattern 8, a spread-out diamond).
*/
#ifndef HSLAM_FEATURES_PATCH_PATTERN_H
#define HSLAM_FEATURES_PATCH_PATTERN_H

namespace hslam
{
//! Number of pixels in a point's patch.
constexpr int kPatternSize = 8;
//! Offsets (du, dv) in pixels of the pattern around the point, at the point's pyramid level (DSO staticPattern 8).
constexpr int kPattern[kPatternSize][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};
//! Largest |offset| of the pattern: points closer than this (plus interpolation room) to the border are skipped.
constexpr int kPatternPadding = 2;
} // namespace hslam

#endif
