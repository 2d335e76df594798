/*
 * H-SLAM for ViSP.
 */
/*!
  \file CornerDetector.h
  \brief FAST corners spread over the image: the corner half of descriptor sharing (paper section 3.1) and the
  keypoints of every new frame the hybrid tracker matches the map into.

  FAST-9 with non-maximum suppression (OpenCV) on the 8-bit image, corners closer than a border to the image edge
  dropped (their ORB descriptor would leave the image). Corners are then taken strongest first under two rules: no
  two closer than a minimum distance, and at most a share of the budget per grid cell, so that one textured area
  cannot take every corner; a second pass gives what is left of the budget to the strongest remaining corners
  (distance rule still applied). The result is that of a single detection at the threshold, computed more cheaply
  when strong corners fill the budget (CornerOptions::strongFirst).

  Threading: free function, no state.
*/
#ifndef HSLAM_FEATURES_CORNER_DETECTOR_H
#define HSLAM_FEATURES_CORNER_DETECTOR_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <opencv2/core.hpp>

#include <vector>

namespace hslam
{
//! FAST thresholds detectCorners() tries first, strictest first, before the configured one (the first is ORB-SLAM's
//! initial FAST threshold).
constexpr int kCornerStrongThresholds[] = {20, 15, 10};

//! Settings of detectCorners().
struct CornerOptions {
  int threshold = 7;           //!< FAST intensity threshold
  int maxCorners = 1000;       //!< corners returned at most (0: none)
  double minDistance = 4.;     //!< no two corners closer than this, pixels (0: no rule)
  int border = 20;             //!< corners closer than this to the image edge are dropped, pixels
  int cellSizePx = 40;         //!< bucketing cell side, pixels
  double cellShareFactor = 2.; //!< a cell takes at most this times its even share of the budget in the first pass
  //! Detect at stricter thresholds first (20, 15, 10) and at \e threshold only when they do not fill the budget:
  //! the same corners, at a fraction of the cost on textured images (see detectCorners()). False: one detection.
  bool strongFirst = true;
};

//! Where the next detectCorners() of the same caller starts its ladder of strict thresholds (a speed hint only).
struct CornerThresholdHint {
  int threshold = kCornerStrongThresholds[0]; //!< strictest FAST threshold to try first; 0: the configured one at once
};

/*!
  FAST corners of \e I (see the file comment), strongest first, level-0 pixel coordinates.
  \param responses : optional, the FAST score of each returned corner.
  \param hint : optional, kept by the caller from one image to the next (updated): the ladder starts at the
  strictest threshold the previous image's corners would have filled. The corners do not depend on it.
*/
VISP_EXPORT void detectCorners(const vpImage<unsigned char> &I, const CornerOptions &options,
                               std::vector<cv::Point2f> &corners, std::vector<float> *responses = nullptr,
                               CornerThresholdHint *hint = nullptr);
} // namespace hslam

#endif
