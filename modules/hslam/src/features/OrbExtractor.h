/*
 * H-SLAM for ViSP.
 */
/*!
  \file OrbExtractor.h
  \brief ORB keypoints spread over the image by a grid (bucketing), with their 256-bit descriptors.

  What it is for: the two-view initializer (and any other feature consumer) needs ORB features that cover the
  whole image, not only its most textured corner. OpenCV's cv::ORB ranks corners globally by Harris score, which
  concentrates them on high-contrast areas; here an over-complete set is detected first, then each grid cell keeps
  its strongest corners (ORB-SLAM2 distributes features per cell the same way, with a quadtree), and the remaining
  budget goes to the globally strongest leftovers.

  Threading: an extractor holds a cv::ORB object and is not thread-safe; use one per thread. No state is kept
  between calls.
*/
#ifndef HSLAM_FEATURES_ORB_EXTRACTOR_H
#define HSLAM_FEATURES_ORB_EXTRACTOR_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include <vector>

namespace hslam
{
//! Settings of OrbExtractor (defaults follow ORB-SLAM2's ORBextractor where it has one).
struct OrbExtractorOptions {
  int maxFeatures = 2000;   //!< features returned at most
  float scaleFactor = 1.2f; //!< ratio between pyramid levels (ORB-SLAM2)
  int levels = 8;           //!< pyramid levels (ORB-SLAM2)
  int fastThreshold = 10;   //!< FAST threshold, intensity units (between ORB-SLAM2's 20 and its fallback 7)
  int cellSizePx = 40;      //!< side of the bucketing cells, level-0 pixels
  int oversampling = 4;     //!< candidates detected per returned feature before bucketing
};

//! ORB detection with grid bucketing.
class VISP_EXPORT OrbExtractor
{
public:
  explicit OrbExtractor(const OrbExtractorOptions &options = OrbExtractorOptions());

  /*!
    Detect and describe.
    \param I : 8-bit image (rectified).
    \param keypoints : output keypoints, level-0 pixel coordinates ((0,0) = centre of the top-left pixel).
    \param descriptors : one 32-byte row per keypoint (CV_8U).
    \exception vpHSlamException::invalidImage when I is empty.
  */
  void extract(const vpImage<unsigned char> &I, std::vector<cv::KeyPoint> &keypoints, cv::Mat &descriptors);

  const OrbExtractorOptions &options() const { return m_options; }

private:
  OrbExtractorOptions m_options;
  cv::Ptr<cv::ORB> m_orb;
};
} // namespace hslam

#endif
