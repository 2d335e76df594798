/*
 * H-SLAM for ViSP.
 */
/*!
  \file SharedPointSelector.h
  \brief Descriptor sharing (paper section 3.1): the points of a new keyframe are FAST corners and DSO's
  region-adaptive gradient pixels, and every one of them gets an oriented ORB descriptor at its own pixel, so the
  same points serve the direct side (patch) and the indirect side (descriptor).

  Corners come on top of the gradient pixels: the gradient selector keeps its whole budget and only a gradient
  pixel on a corner's own pixel is dropped. The issue and ARCHITECTURE.md describe corners taking their cells first
  and gradient pixels filling the rest; that was built and measured first (fast preset, hybrid tracking, median ATE
  over five runs with the point budget moved by up to 2 %): KITTI 06 0.029 m, Tsukuba 0.29 cm, 7-Scenes 0.059 m,
  against 0.024 m, 0.28 cm, 0.055 m with corners on top (direct tracking: 0.022 m, 0.27 cm, 0.051 m). The window's
  photometric BA needs DSO's edge pixels; corners are there for the matching.
  Corner budget: min(Features::maxCorners, Features::cornerShare x the desired count).
  With descriptors off (direct tracking) the selection is exactly the gradient selector's, as before.

  Threading: holds scratch buffers; one per thread (the mapper owns one).
*/
#ifndef HSLAM_FEATURES_SHARED_POINT_SELECTOR_H
#define HSLAM_FEATURES_SHARED_POINT_SELECTOR_H

#include "features/BinaryDescriptor.h"
#include "features/CornerDetector.h"
#include "features/ImagePyramid.h"
#include "features/PixelSelector.h"
#include "features/PointDescriptors.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <unordered_set>
#include <vector>

namespace hslam
{
class VISP_EXPORT SharedPointSelector
{
public:
  /*!
    \param params : selection settings (gradient selector, FAST threshold, corner budget and distance).
    \param withDescriptors : corners and descriptors on (hybrid / indirect tracking) or off (direct).
  */
  SharedPointSelector(const vpHSlamParameters::Features &params, bool withDescriptors);

  //! Which points select() takes. With descriptors off: gradient pixels (none for cornersOnly) whatever is asked.
  enum Kinds {
    cornersAndGradients, //!< the corners, then the gradient pixels (a keyframe's points)
    gradientsOnly,       //!< gradient pixels only (the first keyframe's initial points, see LocalMapper::initialize)
    cornersOnly          //!< the corners only, their budget computed from \e desiredCount as usual
  };

  /*!
    Select the points of a frame: corners (strongest first, see the file comment for their budget), then about
    \e desiredCount gradient pixels.
    \param raw : the rectified 8-bit image (corners are detected on it).
    \param pyramid : its photometric pyramid (gradient selection).
    \param selected : output pixels, corners first.
    \param isCorner : output, per selected pixel.
    \param kinds : which kinds of points (descriptors are computed by describe() for any of them).
  */
  void select(const vpImage<unsigned char> &raw, const ImagePyramid &pyramid, int desiredCount, unsigned int seed,
              std::vector<SelectedPixel> &selected, std::vector<bool> &isCorner, Kinds kinds = cornersAndGradients);

  /*!
    Oriented ORB descriptors at \e pixels of \e raw (PointDescriptors). \e valid is false for pixels too close to
    the border; all false (and descriptors zero) when descriptors are off.
  */
  void describe(const vpImage<unsigned char> &raw, const std::vector<cv::Point2f> &pixels,
                std::vector<OrbDescriptor> &descriptors, std::vector<bool> &valid, std::vector<float> &anglesDeg);

  bool withDescriptors() const { return m_withDescriptors; }
  //! Corners taken by the last select().
  int lastCorners() const { return m_lastCorners; }

private:
  vpHSlamParameters::Features m_params;
  bool m_withDescriptors;
  PixelSelector m_gradients;
  PointDescriptors m_descriptors;
  std::unordered_set<long long> m_cornerPixels;
  std::vector<cv::Point2f> m_corners;
  CornerThresholdHint m_cornerHint; //!< where the next keyframe's corner detection starts (speed only)
  std::vector<SelectedPixel> m_gradientPixels;
  int m_lastCorners = 0;
};
} // namespace hslam

#endif
